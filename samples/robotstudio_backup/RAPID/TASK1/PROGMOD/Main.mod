MODULE Main
    ! Motions only: the targets live in Data.mod, the work object in user.sys.
    PROC main()
        Park;
        MoveL p10,v200,z10,tGun\WObj:=wCar;
        Weld p20;
        Weld pSeam;
        Park;
    ENDPROC
    PROC Weld(robtarget p)
        ! Approach 50 mm above, weld, retract.
        MoveL Offs(p,0,0,50),v200,z10,tGun\WObj:=wCar;
        MoveL p,v50,fine,tGun\WObj:=wCar;
        MoveL RelTool(p,0,0,-50),v200,z10,tGun\WObj:=wCar;
    ENDPROC
ENDMODULE
