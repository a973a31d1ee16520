MODULE Signs
  VAR num a×b := 1;
ENDMODULE
