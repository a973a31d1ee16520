MODULE Werkstück
  ! Latin-1 letters in names; a stray control byte  in this comment 
  VAR num größe := 2;
  PERS robtarget pÑ := [[10,20,30],[1,0,0,0],[0,0,0,0],[1500,9E9,9E9,9E9,9E9,9E9]];

  PROC Ñandú()
    größe := größe + 1;
    MoveL pÑ, v100, fine, tool0;
  ENDPROC
ENDMODULE
