MODULE Data
    ! Cell data: targets on the car body, taught with the track at 1500 mm.
    TASK PERS tooldata tGun:=[TRUE,[[0,0,150],[1,0,0,0]],[2.5,[0,0,60],[1,0,0,0],0,0,0]];
    CONST robtarget p10:=[[812.5,-120,455],[0,0.7071068,0.7071068,0],[0,0,0,0],[1500,9E9,9E9,9E9,9E9,9E9]];
    CONST robtarget p20:=[[812.5,80,455],[0,0.7071068,0.7071068,0],[0,0,0,0],[1500,9E9,9E9,9E9,9E9,9E9]];
    CONST robtarget pSeam:=[[640,0,420],[0,0.7071068,0.7071068,0],[0,-1,0,0],[2100,9E9,9E9,9E9,9E9,9E9]];
    LOCAL CONST robtarget pPark:=[[300,0,900],[0,0.7071068,0.7071068,0],[0,0,0,0],[500,9E9,9E9,9E9,9E9,9E9]];
    PROC Park()
        MoveJ pPark,v500,fine,tGun;
    ENDPROC
ENDMODULE
