MODULE Hand9e9
  ! Hand-written touch-up module: every way people write "not connected"
  ! and numbers in every style the controller accepts.
  PERS tooldata tPen:=[TRUE,[[0,0,152.5],[1,0,0,0]],[0.4,[0,0,60],[1,0,0,0],0,0,0]];
  PERS wobjdata wTable:=[FALSE,TRUE,"",[[2400,650,720.5],[1,0,0,0]],[[0,0,0],[1,0,0,0]]];
  CONST robtarget pA:=[[10,20,30],[0,1,0,0],[0,0,0,0],[2350,9E9,9E9,9E9,9E9,9E9]];
  CONST robtarget pB:=[[10.5,-20.25,.5],[0,1.,0,0],[-1,0,-1,1],[2400.0,9E+09,9E+9,9e9,9e+09,9E+009]];
  CONST robtarget pC:=[ [ -1.5E+2 , 2.5e1 , 0 ] , [ 0.0 , 0.707107 , -0.707107 , 0.0 ] , [ 0 , -1 , 0 , 0 ] , [ 2450 , 9E9 , 9E9 , 9E9 , 9E9 , 9E9 ] ];
  ! an expression inside a target: x is not a literal
  CONST num xOff:=12.5;
  VAR robtarget pD:=[[xOff*2,0,100],[0,1,0,0],[0,0,0,0],[2500,9E9,9E9,9E9,9E9,9E9]];
  CONST robtarget pE:=[[0,0,0],[0,1,0,0],[0,0,0,0],[- 5,9E9,9E9,9E9,9E9,9E9]];

  PROC Draw()
    MoveJ pA, v200, z5, tPen\WObj:=wTable;
    movel pB,v100,fine,tPen\wobj:=wTable;
    MOVEL pC, v100, z1, tPen \WObj:=wTable;
    MoveL pD,v50,z1,tPen,\WObj:=wTable;
    MoveL pE,v50,fine,tPen\WObj:=wTable;
    MoveL Offs(pA, 0, 0, .5), v50, fine, tPen\WObj:=wTable;
  ENDPROC
ENDMODULE
