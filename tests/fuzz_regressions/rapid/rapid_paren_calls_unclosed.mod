MODULE m
PROC p()
  X(
  Y(1)
  (2);
  %"a"(3)%;
  EGMActJoint e\
\
J1:=l;
ENDPROC
