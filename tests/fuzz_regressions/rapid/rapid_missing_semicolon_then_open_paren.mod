MODULE m
PROC p()
  WaitTime 1.000
  MoveL [[1,2,3],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]],v100,z1,tool0;
  Hand_MoveTo(
ENDPROC
ENDMODULE