MODULE IdiomsSeenInTheField
	!! Constructs collected from public controller backups and generator output,
	!! rewritten for trackfix: tabs, MultiMove, force control, sensor frames.
	TASK PERS tasks tlAll{2}:=[["T_ROB1"],["T_ROB2"]];
	VAR syncident syncA;
	LOCAL PERS robtarget pProbe:=[[212.5,480.25,-1210.75],[3.09086E-08,-0.707107,-0.707107,-3.09086E-08],[0,0,-2,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
	CONST robtarget pFar:=[[300,-10,100],[0,0,1,0],[0,0,0,0],[1E+10,1E+10,1E+10,1E+10,1E+10,1E+10]];
	LOCAL PERS wobjdata wSensor:=[FALSE,TRUE,"",[[0,0,0],[0.707107,0.707107,0,0]],[[0,0,0],[1,0,0,0]]];
	LOCAL PERS tooldata tProbe:=[TRUE,[[-31.5,-290.25,66.75],[0.707107,0.707107,0,0]],[4,[80,0,60],[1,0,0,0],0.01,0.01,0.01]];
	PERS tooldata tFc:=[TRUE,[[0,0,310],[1,0,0,0]],[12,[0,0,120],[1,0,0,0],0,0,0]];
	PERS wobjdata wBed:=[FALSE,TRUE,"",[[2500,-400,700],[1,0,0,0]],[[0,0,0],[1,0,0,0]]];
	CONST robtarget pBed:=[[-450,220,60],[1.04259E-05,-0.999952,-0.00961003,-0.00172456],[1,-1,-1,0],[2950.5,9E+09,9E+09,9E+09,9E+09,9E+09]];
	VAR num nStep:=380;

	PROC Sync()
		ConfL\Off;
		SyncMoveOn syncA, tlAll;
		MoveAbsJ [[80.5,-17,48.25,85.75,96.5,-31.75],[3300.5,9E9,9E9,9E9,9E9,9E9]]\ID:=10,v500,fine,tool0;
		MoveJ [[610.5,2320.25,1040.5],[0.5,0.5,0.5,0.5],[0,0,-2,0],[3070.75,9E9,9E9,9E9,9E9,9E9]]\ID:=20,v500,fine,tool0 \WObj:=wobj0;
		SyncMoveOff syncA;
		MoveL pFar,v100,z1,tool0\WObj:=WObj0;
	ENDPROC

	PROC Probe()
		VAR pose poseAdj;
		wSensor.uframe:=[[0,0,0],OrientZYX(ATan2(pProbe.trans.y,pProbe.trans.x),0,0)];
		pProbe:=CRobT(\Tool:=tProbe\WObj:=wSensor);
		pProbe:=RelTool(pProbe,0,0,0\Rz:=+90);
		WHILE ((abs(poseAdj.trans.x)>0.05) OR (abs(poseAdj.trans.y)>0.05)) AND nStep<1000 DO
			MoveL pProbe,v20,fine,tProbe\WObj:=wSensor;
			WaitUntil\InPos,TRUE;
			TPWrite "dx [mm] "\Num:=poseAdj.trans.x;
			poseAdj.trans.x:=-(((poseAdj.trans.x+1)/2)-0.5);
			STOP;
		ENDWHILE
	ENDPROC

	PROC Press()
		FCSupvForce\Zmax:=1000;
		FOR i FROM 0 TO 4 DO
			IF (i MOD 2)=0 THEN
				MoveJ Offs(pBed,0,i*nStep,100),v500,z5,tFc\WObj:=wBed;
				FCPress1LStart Offs(pBed,-25,i*nStep,50),v20,\Fz:=140,15,\ForceChange:=75\PosSupvDist:=100,z5,tFc\WObj:=wBed;
				FCPressEnd Offs(pBed,-300,i*nStep,75),v50,\DeactOnly,tFc\WObj:=wBed;
				MoveJ Offs(Reltool(pBed,0,0,-100\Rz:=-90),0,450,0),v100,fine,tFc\WObj:=wBed;
			ENDIF
		ENDFOR
	ENDPROC
ENDMODULE
