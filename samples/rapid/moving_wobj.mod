MODULE MovingWobj
  ! Work object carried by a positioner (mechanical unit STN1): the user frame
  ! is moved by the unit, so trackfix must not transform these targets.
  PERS wobjdata wStn1:=[FALSE,FALSE,"STN1",[[0,0,0],[1,0,0,0]],[[0,0,250],[1,0,0,0]]];
  PERS tooldata tTorch:=[TRUE,[[-35.2,0,402.6],[0.923880,0,0.382683,0]],[3.2,[0,0,120],[1,0,0,0],0,0,0]];
  CONST robtarget pSeam1:=[[-150,0,20],[0.270598,0.653281,0.653281,-0.270598],[0,0,0,0],[2500,0,9E9,9E9,9E9,9E9]];
  CONST robtarget pSeam2:=[[150,0,20],[0.270598,0.653281,0.653281,-0.270598],[0,0,0,0],[2500,90,9E9,9E9,9E9,9E9]];

  PROC Seam()
    ActUnit STN1;
    MoveJ pSeam1, v500, z10, tTorch\WObj:=wStn1;
    ArcL pSeam2, v20, seam1, weld1, fine, tTorch\WObj:=wStn1;
    DeactUnit STN1;
  ENDPROC
ENDMODULE
