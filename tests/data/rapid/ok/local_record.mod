MODULE Records
  ! records private to the module and to the task
  LOCAL RECORD span_t
    num lo;
    num hi;
  ENDRECORD

  TASK RECORD pair_t
    num a;
    num b;
  ENDRECORD

  LOCAL VAR span_t reach := [0, 8000];
ENDMODULE
