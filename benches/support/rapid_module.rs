//! The generated RAPID module the parse and command benches share (and the shape
//! `scripts/perf-compare.py` writes), so their figures are of the same input.

/// A RobotStudio-style module of about `mb` megabytes: robtarget declarations along an 8 m
/// track, then a routine that visits them with `MoveL`, `Offs` and comments, CRLF line ends.
pub(crate) fn module(mb: usize) -> Vec<u8> {
    use std::fmt::Write as _;
    let target = mb * 1_000_000;
    let mut decls = String::with_capacity(target / 2 + 1024);
    let mut moves = String::with_capacity(target / 2 + 1024);
    decls.push_str("%%%\r\n  VERSION:1\r\n  LANGUAGE:ENGLISH\r\n%%%\r\n\r\nMODULE Bench\r\n");
    decls.push_str("  PERS tooldata tGun:=[TRUE,[[12.5,-3.2,412.8],[0.965926,0,0.258819,0]],[48.5,[0,0,180],[1,0,0,0],0.9,1.1,0.6]];\r\n");
    decls.push_str("  TASK PERS wobjdata wCar:=[FALSE,TRUE,\"\",[[1520.3,-1850.75,612.4],[1,0,0,0]],[[150,0,0],[1,0,0,0]]];\r\n");
    moves.push_str("  PROC main()\r\n");
    let mut i = 0usize;
    while decls.len() + moves.len() < target {
        let s = 150.0 + (i % 7700) as f64;
        let x = s - 1670.3 + (i % 37) as f64 * 0.37;
        let _ = write!(
            decls,
            "  CONST robtarget p{i}:=[[{x:.2},-{:.2},{:.2}],[0.000000,0.707107,0.707107,0.000000],[0,0,-1,0],[{s:.1},9E+09,9E+09,9E+09,9E+09,9E+09]];\r\n",
            700.0 + (i % 13) as f64,
            250.0 + (i % 29) as f64 * 12.5
        );
        if i.is_multiple_of(10) {
            let _ = write!(moves, "    ! group {}\r\n", i / 10);
            let _ = write!(
                moves,
                "    MoveL Offs(p{i},0,0,100), v1000, z10, tGun\\WObj:=wCar;\r\n"
            );
        }
        let _ = write!(moves, "    MoveL p{i}, v1000, z10, tGun\\WObj:=wCar;\r\n");
        i += 1;
    }
    moves.push_str("  ENDPROC\r\nENDMODULE");
    decls.push_str(&moves);
    decls.into_bytes()
}
