MODULE JointsOnly
  ! Axis positions only: service, home and maintenance poses.
  CONST jointtarget jHome:=[[0,-30,30,0,90,0],[4000,9E9,9E9,9E9,9E9,9E9]];
  CONST jointtarget jService:=[[90,0,0,0,45,0],[7600,9E9,9E9,9E9,9E9,9E9]];
  CONST jointtarget jTipDress:=[[-45.5,12.25,-8,0.5,60,-90],[1200.5,9E+09,9E+09,9E+09,9E+09,9E+09]];
  VAR jointtarget jNow;

  PROC GoHome()
    jNow:=CJointT();
    MoveAbsJ jHome\NoEOffs, v1000, fine, tool0;
  ENDPROC

  PROC GoService()
    MoveAbsJ jService, v500, fine, tool0;
    MoveAbsJ [[0,0,0,0,30,0],[4000,9E9,9E9,9E9,9E9,9E9]]\NoEOffs, v200, fine, tool0;
    MoveAbsJ jTipDress, v200, z10, tool0;
  ENDPROC
ENDMODULE
