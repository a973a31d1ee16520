MODULE Open
  PROC main()
    IF TRUE THEN
      Stop;
ENDMODULE
