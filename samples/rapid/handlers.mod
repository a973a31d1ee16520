MODULE Handlers
  ! Error handlers, late binding, interrupts and editor placeholders.
  CONST robtarget pPick:=[[450,-120,310],[0,0.707107,0.707107,0],[-1,0,-1,0],[3200,9E9,9E9,9E9,9E9,9E9]];
  CONST robtarget pPlace:=[[450,380,310],[0,0.707107,0.707107,0],[0,0,-1,0],[3650,9E9,9E9,9E9,9E9,9E9]];
  VAR intnum irStop;
  VAR num nRetries:=0;
  VAR string sRoutine:="Cycle";
  VAR errnum ERR_GRIP:=-1;
  <DDN>

  PROC Main()
    CONNECT irStop WITH StopTrap;
    ISignalDI diStop, 1, irStop;
    BookErrNo ERR_GRIP;
    %sRoutine + "_" + NumToStr(1, 0)%;
    %"Check" + "Part"% \Quiet, 2;
    <SMT>
    Pick;
  ENDPROC

  PROC Pick()
    MoveJ Offs(pPick,0,0,100), v1000, z50, tool0;
    MoveL pPick, v200, fine, tool0;
    IF NOT diGripOk THEN
      RAISE ERR_GRIP;
    ENDIF
    MoveL pPlace, v200, fine, tool0;
  ERROR (ERR_GRIP, ERR_WAITSUPTIME)
    nRetries := nRetries + 1;
    IF nRetries < 3 THEN
      RETRY;
    ELSEIF nRetries < 5 THEN
      TRYNEXT;
    ELSE
      RAISE;
    ENDIF
  UNDO
    Reset doGrip;
  BACKWARD
    MoveL pPick, v100, fine, tool0;
  ENDPROC

  PROC Unfinished()
    IF <EXP> THEN
      <SMT>
    ENDIF
    MoveL <EXP>, v100, <EXP>, tool0;
    <ARG>;
  ENDPROC

  TRAP StopTrap
    StopMove;
    WHILE TRUE DO
      WaitTime 0.5;
      GOTO done;
    ENDWHILE
    done:
    StartMove;
  ENDTRAP
ENDMODULE
