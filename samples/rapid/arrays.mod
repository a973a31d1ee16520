MODULE Arrays
  ! Pallet grid: robtarget arrays with one and two dimensions.
  PERS tooldata tGripper:=[TRUE,[[0,0,220],[1,0,0,0]],[3.5,[0,0,90],[1,0,0,0],0,0,0]];
  PERS wobjdata wPallet:=[FALSE,TRUE,"",[[5200,-900,150],[0.707107,0,0,0.707107]],[[0,0,0],[1,0,0,0]]];
  CONST robtarget pRow{3}:=[
    [[0,0,50],[0,1,0,0],[0,0,0,0],[5100,9E9,9E9,9E9,9E9,9E9]],
    [[200,0,50],[0,1,0,0],[0,0,0,0],[5300,9E9,9E9,9E9,9E9,9E9]],
    [[400,0,50],[0,1,0,0],[0,0,0,0],[5500,9E9,9E9,9E9,9E9,9E9]]];
  CONST robtarget pGrid{2,2}:=[[[[0,300,50],[0,1,0,0],[0,0,0,0],[5100,9E9,9E9,9E9,9E9,9E9]],[[200,300,50],[0,1,0,0],[0,0,0,0],[5300,9E9,9E9,9E9,9E9,9E9]]],[[[0,500,50],[0,1,0,0],[0,0,0,0],[5100,9E9,9E9,9E9,9E9,9E9]],[[200,500,50],[0,1,0,0],[0,0,0,0],[5300,9E9,9E9,9E9,9E9,9E9]]]];
  VAR num nCount{2,2}:=[[0,0],[0,0]];

  PROC Stack()
    FOR i FROM 1 TO 3 DO
      MoveL pRow{i}, v500, fine, tGripper\WObj:=wPallet;
    ENDFOR
    FOR r FROM 1 TO 2 DO
      FOR c FROM 1 TO 2 STEP 1 DO
        MoveL Offs(pGrid{r,c},0,0,100), v1000, z20, tGripper\WObj:=wPallet;
        nCount{r,c}:=nCount{r,c}+1;
      ENDFOR
    ENDFOR
    MoveL pGrid{ 2, 1 }, v100, fine, tGripper\WObj:=wPallet;
  ENDPROC
ENDMODULE
