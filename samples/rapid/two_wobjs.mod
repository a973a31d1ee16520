MODULE TwoWobjs
  ! One target reused with two work objects: left and right fixture.
  ! trackfix must flag pShared: it cannot be transformed for both.
  PERS wobjdata wLeft:=[FALSE,TRUE,"",[[3000,-1200,800],[1,0,0,0]],[[0,0,0],[1,0,0,0]]];
  PERS wobjdata wRight:=[FALSE,TRUE,"",[[3000,1200,800],[0,0,0,1]],[[0,0,0],[1,0,0,0]]];
  PERS tooldata tClamp:=[TRUE,[[0,0,180],[1,0,0,0]],[2,[0,0,60],[1,0,0,0],0,0,0]];
  CONST robtarget pShared:=[[120,40,15],[0,1,0,0],[0,0,0,0],[3000,9E9,9E9,9E9,9E9,9E9]];
  CONST robtarget pLeftOnly:=[[220,40,15],[0,1,0,0],[0,0,0,0],[3100,9E9,9E9,9E9,9E9,9E9]];

  PROC Both()
    MoveL pShared, v200, fine, tClamp\WObj:=wLeft;
    MoveL pLeftOnly, v200, fine, tClamp\WObj:=wLeft;
    MoveL pShared, v200, fine, tClamp\WObj:=wRight;
  ENDPROC
ENDMODULE
