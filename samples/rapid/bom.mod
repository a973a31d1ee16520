MODULE WithBom
  ! Saved as UTF-8 with a byte order mark; a comment in UTF-8: Schweißpunkt
  CONST robtarget pBom:=[[300,-50,620],[0.5,0.5,0.5,0.5],[0,0,1,0],[6400,9E9,9E9,9E9,9E9,9E9]];

  PROC Run()
    MoveJ pBom, v500, z10, tool0;
    TPWrite "Größe ok";
  ENDPROC
ENDMODULE
