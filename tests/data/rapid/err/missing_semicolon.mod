MODULE Broken
  CONST robtarget p1 := [[1,2,3],[1,0,0,0],[0,0,0,0],[500,9E9,9E9,9E9,9E9,9E9]]
  PROC main()
    MoveL p1, v100, fine, tool0;
  ENDPROC
ENDMODULE
