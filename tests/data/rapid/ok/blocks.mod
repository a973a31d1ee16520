%%%
  VERSION:1
  LANGUAGE:ENGLISH
%%%
MODULE Blocks(SYSMODULE, NOSTEPIN)
  CONST num n := 3;

  FUNC num twice(num x)
    RETURN 2 * x;
  ENDFUNC

  PROC main()
    FOR i FROM 1 TO n DO
      IF i = 2 THEN
        TPWrite "two";
      ELSEIF i > 2 THEN
        Stop;
      ELSE
        WaitTime 0.5;
      ENDIF
    ENDFOR
    WHILE FALSE DO
    ENDWHILE
    TEST n
    CASE 1, 2:
      TPWrite "small";
    DEFAULT:
      TPWrite "big";
    ENDTEST
  ERROR
    RETRY;
  ENDPROC
ENDMODULE
