MODULE StationaryTool
  ! The robot holds the part and presents it to a fixed glue nozzle:
  ! robhold TRUE in the work object means a stationary tool.
  PERS tooldata tPart:=[TRUE,[[0,0,95],[1,0,0,0]],[6.2,[0,0,40],[1,0,0,0],0,0,0]];
  PERS wobjdata wNozzle:=[TRUE,TRUE,"",[[1800,900,1100],[0.707107,0,0.707107,0]],[[0,0,0],[1,0,0,0]]];
  CONST robtarget pGlue1:=[[0,-60,0],[1,0,0,0],[0,0,0,0],[1650,9E9,9E9,9E9,9E9,9E9]];
  CONST robtarget pGlue2:=[[0,60,0],[1,0,0,0],[0,0,0,0],[1650,9E9,9E9,9E9,9E9,9E9]];

  PROC Glue()
    MoveL pGlue1, v100, fine, tPart\WObj:=wNozzle;
    MoveL pGlue2, v50, fine, tPart\WObj:=wNozzle;
  ENDPROC
ENDMODULE
