%%%
  VERSION:1
  LANGUAGE:ENGLISH
%%%

MODULE CellIdioms
  ! Constructs met in public controller backups and generator output (second round),
  ! written for trackfix: transfer cell on a 6 m track, gripper, socket link, EGM.

  RECORD seamPoint
    robtarget where;
    num speedMmps;
  Endrecord

  RECORD boxSlot
    bool used; ! slot taken
    num layer;
  ENDRECORD

  pers bool bCellReady:=FALSE;
  Var num nLayer;
  PERS tooldata tGripper:=[TRUE,[[0,0,212.5],[1,0,0,0]],[4.2,[0,0,90],[1,0,0,0],0.01,0.01,0.01]];
  PERS tooldata tActive;
  TASK PERS wobjdata wConveyor:=[FALSE,TRUE,"",[[2250,-640,410],[0.707107,0,0,0.707107]],[[0,0,0],[1,0,0,0]]];
  PERS seamPoint seamA{2}:=[[[[10,0,5],[0,0.707107,0.707107,0],[0,0,1,1],[3120.5,9E+09,9E+09,9E+09,9E+09,9E+09]],12],[[[410,0,5],[0,0.707107,0.707107,0],[0,0,1,1],[3120.5,9E+09,9E+09,9E+09,9E+09,9E+09]],12]];
  PERS boxSlot slots{3}:=
  [
  [FALSE,1],
  [TRUE,2],
  [FALSE,3]
  ];
  CONST jointtarget jPark:=[[0,-20,30,0,80,0],[0,9E+009,9E+009,9E+009,9E+009,9E+009]];
  CONST robtarget pPick:=[[120.4,-35,260],[0.00872654,0,0.999962,0],[-1,0,-1,0],[1850,9E+09,9E+09,9E+09,9E+09,9E+09]]; ! over the conveyor
  CONST robtarget pDrop    := [[640,210,95.5],[0,0.382683,0.92388,0],[0,-1,0,1],[4425.25,9E+09,9E+09,9E+09,9E+09,9E+09]]; !pallet corner
  VAR robtarget pNext;
  VAR robtarget pSent;
  VAR extjoint exTrack;
  VAR socketdev sockPlc;
  VAR egmident egmId;
  CONST egm_minmax egmLimit:=[-0.5,0.5]; ! degrees

  PROC main()
    CONNECT iStop WITH tStop;
    Gripper_Open(25);
    TPWrite("Layer " + NumToStr(nLayer,0) + " of " + NumToStr(MaxLayer(),0));
    IF (bCellReady)
      StartCycle;
    MoveAbsJ jPark\NoEOffs,v1000,z50,tool0;
    MoveAbsJ ArmOnly(jPark)\NoEOffs,v1000,fine,tool:=tGripper;
    TEST nLayer <= 3
      CASE nLayer <= 1:
        MoveJ Offs(pPick, 0, 0, 150), v1000, z50, tGripper, \WObj:= wConveyor;
      CASE nLayer <=3: !upper layers
        MoveJ Offs(pPick, 0, 0, 300), v1000, z50, tGripper, \WObj:= wConveyor;
    ENDTEST
    MoveL pPick\ID:=nStep+1,v200,fine,tool:=tGripper\WObj:=wConveyor;
    SeamL seamA{1}.where\id:=10,v100,seamWeld,wd1\weave:=weave1,z1,tGripper\WObj:=wConveyor\Track:=track0;
    MoveC [[600,200,95.5],[0,0.382683,0.92388,0],[0,-1,0,1],[4425.25,9E+09,9E+09,9E+09,9E+09,9E+09]],pDrop,v300,fine,tGripper\WObj:=wConveyor;
    WaitTime .25;
    SocketClose(sockPlc);
    RETURN ;
  ERROR
    IF ERRNO=ERR_REFUNKPRC THEN
      TRYNEXT;
    ENDIF
  ENDPROC

  PROC FromPlc(num x, num y, num q1, num q2, num q3, num q4)
    pSent :=[[x,y,95.5],
             [q1,q2,q3,q4],
             [0,-1,0,1],
             exTrack];
    MoveL pSent, v500, fine, tGripper \WObj:=wConveyor ;
  ENDPROC

  PROC RunEgm(\switch Joint ,\switch Pose )
    EOffsSet [0,0,0,0,0,0];
    EGMActJoint egmId\Tool:=tGripper\WObj:=wConveyor\
    J1:=egmLimit\J2:=egmLimit\J6:=egmLimit
    \LpFilter:=8\SampleRate:=4\MaxSpeedDeviation:=500;
    EGMRunJoint egmId,EGM_STOP_HOLD,\J1\J2\J6\CondTime:=10\RampInTime:=0.05;
    TPWrite "EGM state: "\Num:=EGMGetState(egmId);
  ENDPROC

  PROC WaitPart(
    VAR signaldi diPart,
    dionum value
    \switch NoAlarm
    \num MaxWait,
    string message)
    WaitDI diPart,value\MaxTime:=MaxWait\TimeFlag:=bTimeout;
    IF bTimeout AND NOT Present(NoAlarm) ErrWrite\W,"WaitPart",message;
    CheckTrack jPark\ArmOnly?NoAlarm;
  ENDPROC

  Func jointtarget ArmOnly(jointtarget target)
    VAR jointtarget now;
    now:=CJointT();
    target.extax.eax_a:=now.extax.eax_a;
    Return target;
  ENDFUNC

  TRAP tStop
    StopMove;
  ENDTRAP
ENDMODULE
