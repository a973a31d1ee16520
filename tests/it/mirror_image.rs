//! A mirror image for another robot of the cell (`transfer --mirror`, `mirror --robot A --to
//! B`) is solved in that robot's own base at the mapped skid: joint targets and configurations
//! (docs/design.md §10, "The transforms with kinematics"). The checks use a forward kinematics
//! written here, the elementary product of the arm's joint transforms, and a Newton solve on it.

use std::path::{Path, PathBuf};

use nalgebra::{Matrix6, Quaternion, Rotation3, Translation3, UnitQuaternion, Vector3, Vector6};

use crate::support::trackfix;

type Pose = nalgebra::Isometry3<f64>;

/// An OPW arm as the bundled models give it (ROS-Industrial's values): lengths in mm, and the
/// controller's joint `θ` to the model's `q = sign·θ − offset`, degrees.
struct Arm {
    a1: f64,
    a2: f64,
    c1: f64,
    c2: f64,
    c3: f64,
    c4: f64,
    signs: [f64; 6],
    offsets: [f64; 6],
}

const IRB4600: Arm = Arm {
    a1: 175.0,
    a2: -175.0,
    c1: 495.0,
    c2: 1095.0,
    c3: 1270.0,
    c4: 135.0,
    signs: [1.0; 6],
    offsets: [0.0, 0.0, -90.0, 0.0, 0.0, 0.0],
};

const KR210: Arm = Arm {
    a1: 330.0,
    a2: -115.0,
    c1: 645.0,
    c2: 1350.0,
    c3: 1420.0,
    c4: 240.0,
    signs: [-1.0, 1.0, 1.0, -1.0, 1.0, -1.0],
    offsets: [0.0, -90.0, 0.0, 0.0, 0.0, 0.0],
};

fn rz(deg: f64) -> Pose {
    Pose::from_parts(
        Translation3::identity(),
        UnitQuaternion::from_axis_angle(&Vector3::z_axis(), deg.to_radians()),
    )
}

fn ry(deg: f64) -> Pose {
    Pose::from_parts(
        Translation3::identity(),
        UnitQuaternion::from_axis_angle(&Vector3::y_axis(), deg.to_radians()),
    )
}

fn tr(x: f64, y: f64, z: f64) -> Pose {
    Pose::translation(x, y, z)
}

impl Arm {
    /// The flange in the robot base: `Rz(q1)·T(a1,0,c1)·Ry(q2)·T(0,0,c2)·Ry(q3)·T(a2,0,c3)·
    /// Rz(q4)·Ry(q5)·Rz(q6)·T(0,0,c4)`.
    fn forward(&self, j: &[f64; 6]) -> Pose {
        let q: Vec<f64> = (0..6)
            .map(|i| self.signs[i] * j[i] - self.offsets[i])
            .collect();
        rz(q[0])
            * tr(self.a1, 0.0, self.c1)
            * ry(q[1])
            * tr(0.0, 0.0, self.c2)
            * ry(q[2])
            * tr(self.a2, 0.0, self.c3)
            * rz(q[3])
            * ry(q[4])
            * rz(q[5])
            * tr(0.0, 0.0, self.c4)
    }

    /// The joints near `start` whose flange is `target`: Newton steps on the position and
    /// rotation-vector error with a numeric Jacobian.
    fn solve_near(&self, target: &Pose, start: [f64; 6]) -> [f64; 6] {
        let error = |j: &[f64; 6]| {
            let f = self.forward(j);
            let dp = target.translation.vector - f.translation.vector;
            let dr = (target.rotation * f.rotation.inverse()).scaled_axis();
            Vector6::new(
                dp.x,
                dp.y,
                dp.z,
                dr.x * 1000.0,
                dr.y * 1000.0,
                dr.z * 1000.0,
            )
        };
        let mut j = start;
        for _ in 0..30 {
            let e = error(&j);
            if e.norm() < 1e-10 {
                break;
            }
            let mut jac = Matrix6::zeros();
            for k in 0..6 {
                let mut h = j;
                h[k] += 1e-6;
                jac.set_column(k, &((error(&j) - error(&h)) / 1e-6));
            }
            let step = jac.lu().solve(&e).expect("a regular pose");
            for k in 0..6 {
                j[k] += step[k];
            }
        }
        j
    }
}

/// `R = Rz·Ry·Rx` of degrees, at `(x, y, z)`.
fn pose_zyx(x: f64, y: f64, z: f64, rx: f64, ry: f64, rz: f64) -> Pose {
    let r = Rotation3::from_euler_angles(rx.to_radians(), ry.to_radians(), rz.to_radians());
    Pose::from_parts(
        Translation3::new(x, y, z),
        UnitQuaternion::from_rotation_matrix(&r),
    )
}

/// A robot base of the sample cell at skid `s`: `Trans(s·a)·B_0` (samples/cell.toml).
fn base(robot: &str, s: f64) -> Pose {
    let (b0, a) = match robot {
        "r1" | "k1" => (
            pose_zyx(0.016, -3499.087, -1.496, 0.000412, -0.000064, 90.000710),
            Vector3::new(1.0, -0.0000032, 0.0000014),
        ),
        _ => (
            pose_zyx(0.000, -202.033, -0.720, -0.000745, 0.000196, -89.999828),
            Vector3::new(1.0, 0.0000003, 0.0000022),
        ),
    };
    Translation3::from(a.normalize() * s) * b0
}

fn numbers(text: &str) -> Vec<f64> {
    text.split(|c: char| !(c.is_ascii_digit() || matches!(c, '.' | '-' | 'E' | 'e' | '+')))
        .filter_map(|t| t.parse().ok())
        .collect()
}

/// The numbers of the literal declared as `name` in `text`.
fn literal(text: &str, name: &str) -> Vec<f64> {
    let line = text
        .lines()
        .find(|l| l.contains(&format!(" {name}:=")) || l.contains(&format!(" {name}=")))
        .unwrap();
    let at = line.find(['[', '{']).unwrap();
    numbers(&line[at..])
}

fn distance(a: &Pose, b: &Pose) -> (f64, f64) {
    (
        (a.translation.vector - b.translation.vector).norm(),
        a.rotation.angle_to(&b.rotation).to_degrees(),
    )
}

/// `jT` and `pT` are one flange pose on r1 at skid 3000 (`pT` = `B1(3000)·FK(jT)`, tool0 in
/// wobj0): a joint target and its Cartesian twin.
const TWINS: &str = "MODULE Twin
  CONST jointtarget jT:=[[5,20,10,40,60,-30],[3000.0,9E9,9E9,9E9,9E9,9E9]];
  CONST robtarget pT:=[[2772.5670,-1761.7710,927.7176],[0.1591504,0.7545567,-0.5855842,-0.2498130],[0,0,-1,0],[3000.0,9E9,9E9,9E9,9E9,9E9]];
  PROC main()
    MoveAbsJ jT, v100, fine, tool0;
    MoveJ pT, v100, fine, tool0;
  ENDPROC
ENDMODULE
";

/// The pose of a RAPID robtarget's numbers `[x, y, z, q1, q2, q3, q4, …]`.
fn robtarget(n: &[f64]) -> Pose {
    let q = UnitQuaternion::from_quaternion(Quaternion::new(n[3], n[4], n[5], n[6]));
    Pose::from_parts(Translation3::new(n[0], n[1], n[2]), q)
}

fn joints(n: &[f64]) -> [f64; 6] {
    [n[0], n[1], n[2], n[3], n[4], n[5]]
}

/// The sample cell's text, its paths made absolute (to be written elsewhere), with its text
/// `old` (which it has) replaced by `new`.
fn sample_cell_with(old: &str, new: &str) -> String {
    let text = crate::support::sample_cell();
    assert!(text.contains(old), "{old}");
    text.replace(old, new)
}

/// The sample cell with its mirror plane 3 m from the car's: r2's base stands 6 m from the
/// mirror image of r1's, across the track.
fn sample_cell_with_the_plane_elsewhere() -> String {
    sample_cell_with(
        "frame = { x = 0.0, y = -1850.75,",
        "frame = { x = 0.0, y = 1149.25,",
    )
}

/// `trackfix transfer INPUT --cell CELL --from r1 --to r2 --mirror`, then `more` (where it
/// writes, `--diff`): (exit code, stdout, stderr).
fn transfer_mirrored(input: &Path, cell: &str, more: &[&str]) -> (i32, String, String) {
    transfer_mirrored_between(input, cell, "r1", "r2", more)
}

/// [`transfer_mirrored`] from robot `from` to robot `to`.
fn transfer_mirrored_between(
    input: &Path,
    cell: &str,
    from: &str,
    to: &str,
    more: &[&str],
) -> (i32, String, String) {
    let mut args = vec![
        "transfer",
        input.to_str().unwrap(),
        "--cell",
        cell,
        "--from",
        from,
        "--to",
        to,
        "--mirror",
    ];
    args.extend_from_slice(more);
    trackfix(&args)
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// `transfer --mirror` to r2: the joint target and its Cartesian twin, one pose on r1, reach one
/// pose on r2: `FK(jT') = B2(s)⁻¹·pT'` (the track's deviation at that skid is the same for
/// both and drops out). Before, the joint target was mirrored as if r2 stood at the mirror
/// image of r1's base (0.86 mm off on this cell), and the twins ended 0.85 mm apart.
#[test]
fn transfer_mirror_keeps_a_joint_target_with_its_cartesian_twin() {
    let dir = tempfile::tempdir().unwrap();
    let input = write(dir.path(), "twin.mod", TWINS);
    let out = dir.path().join("out.mod");
    // The twins agree on r1 as written.
    let (j, p) = (literal(TWINS, "jT"), literal(TWINS, "pT"));
    let (mm, deg) = distance(
        &IRB4600.forward(&joints(&j)),
        &(base("r1", 3000.0).inverse() * robtarget(&p)),
    );
    assert!(mm < 1e-3 && deg < 1e-5, "{mm} {deg}");
    let (code, _, err) =
        transfer_mirrored(&input, "samples/cell.toml", &["-o", out.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    let text = std::fs::read_to_string(&out).unwrap();
    let (j, p) = (literal(&text, "jT"), literal(&text, "pT"));
    let (mm, deg) = distance(
        &IRB4600.forward(&joints(&j)),
        &(base("r2", 3000.0).inverse() * robtarget(&p)),
    );
    // Within what 4 decimals of a degree on a 2.6 m arm and 4 of a millimetre amount to.
    assert!(
        mm < 0.01 && deg < 3e-4,
        "jT and pT on r2 are {mm:.4} mm / {deg:.5}° apart\n{text}"
    );
    // Not the rule's image: that would put them 0.85 mm apart.
    let rule = [-5.0, 20.0, 10.0, -40.0, 60.0, 30.0];
    let moved = j
        .iter()
        .zip(rule)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(moved > 0.01, "{j:?}");
}

/// `mirror --robot k1 --to k2` writes the Status and Turn k2 reaches the image with from its own
/// base. `XA3Z` is the flange of k1 at `[10, -40, 0.01, 30, 45, 60]` (A3 a hundredth of a degree
/// above 0); on k2, whose base is not quite r1's mirror image, the image is reached with A3 at
/// -0.25° (Turn bit 2 set, T 47). Before, the Turn of the rule's image robot was written (T 43),
/// which k2 reaches the target with in no solution.
#[test]
fn mirror_to_another_kuka_robot_writes_the_configuration_it_reaches_the_image_with() {
    let dir = tempfile::tempdir().unwrap();
    let src = "DEF mir_st( )\n  BAS(#INITMOV,0)\n  BAS(#BASE,0)\n  BAS(#TOOL,0)\n  PTP XA3Z\nEND\n";
    let dat = "DEFDAT mir_st\nDECL E6POS XA3Z={X 4535.5149,Y -950.7022,Z 2508.4088,A -30.81732,B 7.47249,C -90.85244,S 0,T 2,E1 4000.0,E2 0.0,E3 0.0,E4 0.0,E5 0.0,E6 0.0}\nENDDAT\n";
    let input = write(dir.path(), "mir_st.src", src);
    write(dir.path(), "mir_st.dat", dat);
    let out = dir.path().join("out");
    let (code, _, err) = trackfix(&[
        "mirror",
        input.to_str().unwrap(),
        "--cell",
        "samples/cell.toml",
        "--robot",
        "k1",
        "--to",
        "k2",
        "--out-dir",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let text = std::fs::read_to_string(out.join("mir_st.dat")).unwrap();
    let n = literal(&text, "XA3Z");
    // {X, Y, Z, A, B, C, S, T, E1, …}, base 0 (world) and tool 0 (the flange).
    let (status, turn, skid) = (n[6] as u32, n[7] as u32, n[8]);
    let flange = base("k2", skid).inverse() * pose_zyx(n[0], n[1], n[2], n[5], n[4], n[3]);
    // The joints on k2 near the rule's image of the original ones.
    let j = KR210.solve_near(&flange, [-10.0, -40.0, 0.01, -30.0, 45.0, -60.0]);
    let (mm, deg) = distance(&KR210.forward(&j), &flange);
    assert!(mm < 1e-6 && deg < 1e-6, "{j:?}");
    // Turn: bit i is axis i+1 below 0 (KSS "Status and Turn").
    let expected_turn: u32 = (0..6).filter(|&i| j[i] < 0.0).map(|i| 1 << i).sum();
    assert!((j[2] - -0.246).abs() < 0.01, "{j:?}");
    assert_eq!((status, turn), (0, expected_turn), "{j:?}\n{text}");
    assert_eq!(turn, 47);
}

/// The sample cell with the mirror plane elsewhere: r2 at skid 3000 stands 6 m from where the
/// twins' image lies. Both twins are refused, each saying where it is out of reach; before, the
/// joint target was written for r2 without complaint, and the Cartesian one was "out of reach
/// as written" though r1 reaches it as written.
#[test]
fn an_image_robot_that_stands_elsewhere_refuses_both_twins_saying_where() {
    let dir = tempfile::tempdir().unwrap();
    let cell_map = write(
        dir.path(),
        "cell_plane.toml",
        &sample_cell_with_the_plane_elsewhere(),
    );
    let input = write(dir.path(), "twin.mod", TWINS);
    let transfer = |cell: &Path| transfer_mirrored(&input, cell.to_str().unwrap(), &["--diff"]);
    let (code, out, err) = transfer(&cell_map);
    assert_eq!(code, 3, "{err}");
    assert!(out.is_empty(), "{out}");
    for name in ["jT", "pT"] {
        let line = err
            .lines()
            .find(|l| l.contains(&format!("`{name}`")))
            .unwrap_or_else(|| panic!("{err}"));
        assert!(
            line.contains("its mirror image") && line.contains("on robot `r2` at skid 3000.0 mm"),
            "{line}"
        );
        assert!(!line.contains("as written"), "{line}");
    }
}

/// A refusal a later step of a `transfer` makes says which step it is: its "as written" is that
/// step's input, not the file. Without r1's kinematics the mirror has no arm to solve the image
/// with, and r2's `correct` finds its image out of reach (the plane is elsewhere); before, the message said
/// only "out of reach as written", of a target r1 reaches as written.
#[test]
fn a_refusal_of_a_later_step_of_a_transfer_says_which_step() {
    let dir = tempfile::tempdir().unwrap();
    let cell = sample_cell_with_the_plane_elsewhere();
    let without = cell.replace(
        "[robot.r1.kinematics]\nmodel = \"abb_irb4600_40_255\"\n",
        "",
    );
    assert_ne!(without, cell);
    let cell_rules_r1 = write(dir.path(), "cell_r1_rules.toml", &without);
    let input = write(dir.path(), "twin.mod", TWINS);
    let (code, _, err) = transfer_mirrored(&input, cell_rules_r1.to_str().unwrap(), &["--diff"]);
    assert_eq!(code, 3, "{err}");
    let line = err.lines().find(|l| l.contains("`pT`")).unwrap();
    assert!(
        line.contains("(in the transfer's `correct` for robot `r2`, of the target as the steps before it wrote it)"),
        "{line}"
    );
}

/// A skid map that does not put the mirror-image robot at the mirror image of the robot is an
/// error at the cell's `skid_map`, with the map the bases give, for `transfer --mirror` and
/// `mirror --to` alike, and the map is not used. The sample's bases are mirror images along the
/// track to 0.016 mm: `[1, 20]` stands r2 20 mm down its track from r1's image, and r2 then
/// reached the mirrored targets from there (a silent change of its posture, exit 0); `[-1, 8000]`
/// runs the tracks against each other. A map within 1 mm passes, and the way back (r2 to r1)
/// takes its inverse (the sample's `skid_map_from` names r1).
#[test]
fn a_skid_map_that_does_not_put_the_image_robot_at_the_mirror_image_is_an_error_at_the_entry() {
    let dir = tempfile::tempdir().unwrap();
    let input = write(dir.path(), "twin.mod", TWINS);
    let run = |input: &Path, cell: &Path, command: &[&str], out: &[&str]| {
        let mut args = vec![command[0], input.to_str().unwrap(), "--cell"];
        args.push(cell.to_str().unwrap());
        args.extend(&command[1..]);
        args.extend(out);
        trackfix(&args)
    };
    let transfer = ["transfer", "--from", "r1", "--to", "r2", "--mirror"];
    let mirror = ["mirror", "--robot", "r1", "--to", "r2"];
    for (map, line, along) in [
        (
            "[1.0, 20.0]",
            "19.984 mm along its track",
            "and 19.984 mm at 8000.0 (at 8020.0)",
        ),
        (
            "[-1.0, 8000.0]",
            "7999.984 mm along its track",
            "and -8000.016 mm at 8000.0 (at 0.0)",
        ),
    ] {
        let cell = write(
            dir.path(),
            "cell_map.toml",
            &sample_cell_with("skid_map = [1.0, 0.0]", &format!("skid_map = {map}")),
        );
        for command in [&transfer[..], &mirror[..]] {
            let (code, out, err) = run(&input, &cell, command, &["--diff"]);
            assert_eq!(code, 2, "{map} {command:?}: {err}");
            assert!(out.is_empty(), "{out}");
            let first = err.lines().next().unwrap();
            // At the entry: line 71, column 12 of the cell file.
            assert!(
                first.contains("cell_map.toml:71:12: error: skid map "),
                "{first}"
            );
            assert!(
                first.contains(&format!("puts robot `r2`'s base {line} from the mirror image of robot `r1`'s at `r1`'s skid 0.0")),
                "{first}"
            );
            assert!(first.contains(along), "{first}");
            assert!(first.ends_with("the bases give [1, 0.016]"), "{first}");
        }
    }
    // A map within the tolerance of the bases' passes (0.984 mm off), and mirrors back with its
    // inverse, not with itself (1.016 mm off that way): the sample's skid_map_from names r1, so
    // the way back takes the inverse; without it the map is taken as written, an error.
    let cell = write(
        dir.path(),
        "cell_map.toml",
        &sample_cell_with("skid_map = [1.0, 0.0]", "skid_map = [1.0, 1.0]"),
    );
    let there = dir.path().join("there.mod");
    let (code, _, err) = run(&input, &cell, &mirror, &["-o", there.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    let back = ["mirror", "--robot", "r2", "--to", "r1", "--diff"];
    let (code, _, err) = run(&there, &cell, &back, &[]);
    assert_eq!(code, 0, "{err}");
    let (code, _, err) = run(&there, &cell, &back, &["--skid-map", "1,-1"]);
    assert_eq!(code, 0, "{err}");
    let as_written = write(
        dir.path(),
        "cell_as_written.toml",
        &sample_cell_with("skid_map = [1.0, 0.0]", "skid_map = [1.0, 1.0]")
            .replace("skid_map_from = [\"r1\", \"k1\"]", "#"),
    );
    let (code, _, err) = run(&there, &as_written, &back, &[]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("puts robot `r1`'s base 1.016 mm along")
            && err.contains("the bases give [1, -0.016]; its inverse [1, -1] fits"),
        "{err}"
    );
    let (code, _, err) = run(&there, &cell, &back, &["--skid-map", "1,-5"]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.starts_with(
            "error: --skid-map: skid map [1, -5] puts robot `r1`'s base -4.984 mm along"
        ),
        "{err}"
    );
}

/// The module of `TWINS`' target `name` alone: a run whose only change is that target's.
fn twin_alone(name: &str) -> String {
    let (motion, other) = match name {
        "jT" => ("MoveAbsJ jT", "pT:="),
        _ => ("MoveJ pT", "jT:="),
    };
    TWINS
        .lines()
        .filter(|l| !l.contains(other) && (!l.contains("Move") || l.contains(motion)))
        .map(|l| format!("{l}\n"))
        .collect()
}

/// The `mm` and `°` of the summary's largest change, `what` (`largest move` or `largest
/// correction`): `… largest move 531.470 mm / 104.3917° → …`.
fn summary_largest(summary: &str, what: &str) -> (f64, f64) {
    let rest = summary
        .split(&format!("{what} "))
        .nth(1)
        .unwrap_or_else(|| panic!("no {what} in {summary}"));
    let n = numbers(rest.split('°').next().unwrap());
    (n[0], n[1])
}

/// `mirror … --mirror-joints` (with `options` besides) of the joint target `jT` alone, written
/// to `out.mod` in a new folder, the run succeeding: the folder, standard output and error,
/// and the output's text.
fn mirror_joint_target_alone(options: &[&str]) -> (tempfile::TempDir, String, String, String) {
    let dir = tempfile::tempdir().unwrap();
    let input = write(dir.path(), "joint.mod", &twin_alone("jT"));
    let out = dir.path().join("out.mod");
    let mut args = vec!["mirror", input.to_str().unwrap()];
    args.extend_from_slice(options);
    args.extend(["--mirror-joints", "-o", out.to_str().unwrap()]);
    let (code, stdout, err) = trackfix(&args);
    assert_eq!(code, 0, "{err}");
    let text = std::fs::read_to_string(&out).unwrap();
    (dir, stdout, err, text)
}

/// `mirror --robot r1 --to r2 --mirror-joints` of a joint target alone: the summary's largest
/// move is its flange's, each flange in the base of the robot its joints are written for:
/// `FK(jT)` on r1 to `FK(jT')` on r2, to the printed decimals. Before, a joint target's change
/// was recorded as none: "largest move 0.000 mm / 0.0000°".
#[test]
fn mirror_summary_gives_a_joint_targets_flange_move() {
    let (_dir, stdout, err, text) =
        mirror_joint_target_alone(&["--cell", "samples/cell.toml", "--robot", "r1", "--to", "r2"]);
    let (mm, deg) = distance(
        &IRB4600.forward(&joints(&literal(TWINS, "jT"))),
        &IRB4600.forward(&joints(&literal(&text, "jT"))),
    );
    // A1 5° to about -5° swings the flange by some 400 mm: far from the recorded 0.
    assert!(mm > 100.0 && deg > 10.0, "{mm} {deg}\n{text}");
    let (said_mm, said_deg) = summary_largest(&format!("{stdout}{err}"), "largest move");
    assert!(
        (said_mm - mm).abs() <= 0.0005 + 1e-9 && (said_deg - deg).abs() <= 0.00005 + 1e-9,
        "summary {said_mm} mm / {said_deg}°, flange moved {mm:.4} mm / {deg:.5}°\n{err}"
    );
}

/// `transfer --mirror` of a joint target alone reports the correction of its Cartesian twin (one
/// pose on r1, see `TWINS`): what the two tracks and bases add beyond the mirror, the same
/// change of one flange whichever frame it is measured in. Before, a joint target's correction
/// was recorded as none: "largest correction 0.000 mm / 0.0000°".
#[test]
fn transfer_mirror_summary_gives_a_joint_targets_correction_as_its_twins() {
    let dir = tempfile::tempdir().unwrap();
    let largest = |name: &str| {
        let input = write(dir.path(), &format!("{name}.mod"), &twin_alone(name));
        let out = dir.path().join(format!("{name}.out.mod"));
        let (code, stdout, err) =
            transfer_mirrored(&input, "samples/cell.toml", &["-o", out.to_str().unwrap()]);
        assert_eq!(code, 0, "{err}");
        summary_largest(&format!("{stdout}{err}"), "largest correction")
    };
    let (joint, cartesian) = (largest("jT"), largest("pT"));
    assert!(cartesian.0 > 0.1, "{cartesian:?}");
    // The twins end within 0.01 mm / 3e-4° of each other on r2
    // (`transfer_mirror_keeps_a_joint_target_with_its_cartesian_twin`).
    assert!(
        (joint.0 - cartesian.0).abs() < 0.01 && (joint.1 - cartesian.1).abs() < 3e-4,
        "joint target {joint:?}, its Cartesian twin {cartesian:?}"
    );
}

/// `samples/cell_rules.toml` (the sample cell without kinematics), its paths made absolute, with
/// each `(old, new)` of `changes` (which it has) replaced.
fn rules_cell_with(changes: &[(&str, &str)]) -> String {
    let samples = crate::support::root().join("samples");
    let mut text = std::fs::read_to_string(samples.join("cell_rules.toml"))
        .unwrap()
        .replace("\"track/", &format!("\"{}/track/", samples.display()))
        .replace("\"krl/", &format!("\"{}/krl/", samples.display()));
    for (old, new) in changes {
        assert!(text.contains(old), "{old}");
        text = text.replace(old, new);
    }
    text
}

/// The skid position (`eax_a`) of the RAPID target `name` in `text`.
fn skid_of(text: &str, name: &str) -> f64 {
    let n = literal(text, name);
    // A robtarget: x y z, q1…q4, cf1 cf4 cf6 cfx, then eax_a; a jointtarget: six axes.
    n[if n.len() > 12 { 11 } else { 6 }]
}

/// The sample cell with r2 and k2 standing `dx` mm farther along world x (their base at skid 0
/// and r2's profile, measured in world, moved with them), its `[mirror]` skid map lines
/// replaced by `map`, written as `name`. r2 is then r1's mirror image at `s' = s − dx`.
fn cell_with_r2_moved(dir: &Path, name: &str, dx: f64, map: &str) -> PathBuf {
    let samples = crate::support::root().join("samples");
    let profile = std::fs::read_to_string(samples.join("track/r2/profile.toml")).unwrap();
    // Its knots' hash is of the nominal too: left out, as a profile may.
    let moved: String = profile
        .replace(
            "origin = [0.000449,",
            &format!("origin = [{},", 0.000449 + dx),
        )
        .lines()
        .filter(|l| !l.starts_with("data_sha256"))
        .map(|l| format!("{l}\n"))
        .collect();
    assert!(moved.contains(&format!("origin = [{},", 0.000449 + dx)));
    let profile_path = write(dir, "r2_moved.toml", &moved);
    let lines = "skid_map = [1.0, 0.0]    # s' = 1.0·s + 0.0: the tracks are aligned\nskid_map_from = [\"r1\", \"k1\"]  # whose skids s are; a mirror to r1 or k1 takes s = (s' - offset)/scale\n";
    let text = sample_cell_with(lines, &format!("{map}\n"))
        .replace(
            "base = { x = 0.000, y = -202.033,",
            &format!("base = {{ x = {dx:.3}, y = -202.033,"),
        )
        .replace(
            &format!("\"{}\"", samples.join("track/r2/profile.toml").display()),
            &format!("\"{}\"", profile_path.display()),
        );
    write(dir, name, &text)
}

/// A skid map that is not its own inverse takes the skids of the robots `skid_map_from` names:
/// a mirror from one of them takes it as written, a mirror to one its inverse
/// `s = (s' − offset)/scale`. r2 stands 20 mm farther along its track than on the sample cell,
/// so r2 is r1's mirror image at `s' = s − 20`: `[1, -20]` from r1, and on the way back its
/// inverse `[1, 20]`, so the twins' skids go 3000 → 2980 → 3000 and their text comes back.
/// Before, the way back took `[1, -20]` as written (an error at the entry: r1 40 mm off), and
/// only `--skid-map 1,20` passed. Without the key the map is taken as written, and the error
/// the way back says that its inverse fits and which key to add; a key naming the wrong side,
/// a `--skid-map` given the other way round and a mirror whose way is not known are errors
/// saying what to write.
#[test]
fn a_skid_map_goes_the_way_back_inverted_for_the_robots_skid_map_from_names() {
    let dir = tempfile::tempdir().unwrap();
    let input = write(dir.path(), "twin.mod", TWINS);
    let run = |cell: &Path, args: &[&str]| {
        let mut all = vec![args[0], args[1], "--cell", cell.to_str().unwrap()];
        all.extend(&args[2..]);
        trackfix(&all)
    };
    let (there, back) = (dir.path().join("there.mod"), dir.path().join("back.mod"));
    let (there, back) = (there.to_str().unwrap(), back.to_str().unwrap());
    let input = input.to_str().unwrap();
    let to_r2 = ["transfer", input, "--from", "r1", "--to", "r2", "--mirror"];
    let to_r1 = ["transfer", there, "--from", "r2", "--to", "r1", "--mirror"];
    let keyed = cell_with_r2_moved(
        dir.path(),
        "keyed.toml",
        20.0,
        "skid_map = [1.0, -20.0]\nskid_map_from = \"r1\"",
    );
    let (code, _, err) = run(&keyed, &[&to_r2[..], &["-o", there]].concat());
    assert_eq!(code, 0, "{err}");
    let there_text = std::fs::read_to_string(there).unwrap();
    for name in ["jT", "pT"] {
        assert_eq!(skid_of(&there_text, name), 2980.0, "{name}\n{there_text}");
    }
    let (code, _, err) = run(&keyed, &[&to_r1[..], &["-o", back]].concat());
    assert_eq!(code, 0, "{err}");
    let back_text = std::fs::read_to_string(back).unwrap();
    for name in ["jT", "pT"] {
        assert_eq!(skid_of(&back_text, name), 3000.0, "{name}\n{back_text}");
        // Back where they were: the transfer writes a target its steps bring back as written.
        let line = |text: &str| {
            let at = format!(" {name}:=");
            text.lines().find(|l| l.contains(&at)).unwrap().to_owned()
        };
        assert_eq!(line(&back_text), line(TWINS), "{back_text}");
    }

    // Without the key: the same image, and the way back is an error that names the key.
    let plain = cell_with_r2_moved(dir.path(), "plain.toml", 20.0, "skid_map = [1.0, -20.0]");
    let plain_there = dir.path().join("plain.mod");
    let (code, _, err) = run(
        &plain,
        &[&to_r2[..], &["-o", plain_there.to_str().unwrap()]].concat(),
    );
    assert_eq!(code, 0, "{err}");
    assert_eq!(std::fs::read_to_string(&plain_there).unwrap(), there_text);
    let mut said = String::new();
    let mut record = |what: &str, (code, out, err): (i32, String, String)| {
        assert_eq!(code, 2, "{what}: {err}");
        assert!(out.is_empty(), "{what}: {out}");
        let err = err.replace(dir.path().to_str().unwrap(), "<tmp>");
        said.push_str(&format!("$ {what}\n{err}\n"));
    };
    record(
        "transfer --from r2 --to r1 --mirror, no skid_map_from",
        run(&plain, &[&to_r1[..], &["--diff"]].concat()),
    );
    let wrong = cell_with_r2_moved(
        dir.path(),
        "wrong.toml",
        20.0,
        "skid_map = [1.0, -20.0]\nskid_map_from = \"r2\"",
    );
    record(
        "transfer --from r1 --to r2 --mirror, skid_map_from = \"r2\"",
        run(&wrong, &[&to_r2[..], &["--diff"]].concat()),
    );
    record(
        "transfer --from r2 --to r1 --mirror --skid-map 1,-20",
        run(
            &keyed,
            &[&to_r1[..], &["--skid-map", "1,-20", "--diff"]].concat(),
        ),
    );
    record(
        "mirror --robot r2 (no --to), skid_map_from = \"r1\"",
        run(&keyed, &["mirror", there, "--robot", "r2", "--diff"]),
    );
    insta::assert_snapshot!("skid_map_direction_errors", said);
}

/// The declared targets of RAPID `text`, each by name with its literal's numbers.
fn numbers_of_targets(text: &str) -> Vec<(String, Vec<f64>)> {
    text.lines()
        .filter(|l| l.contains("robtarget ") || l.contains("jointtarget "))
        .filter_map(|l| {
            let name = l.split(":=").next()?.split_whitespace().last()?.to_owned();
            Some((name.clone(), literal(text, &name)))
        })
        .collect()
}

/// Tracks that run opposite ways: r2's skid counted from the far end, its base at skid 0 at
/// x = 8000 and its track axis −x (its profile the sample's knots at `8000 − s`, its nominal
/// from there along −x), with the map `[-1, 8000]`. The physical cell is the sample's, so
/// `transfer --mirror` of spot_line writes every target's numbers as the sample cell does (to
/// 1e-4, a joint's last decimal) and its skid at `8000 − s`, and the way back gives the bytes
/// the sample cell's way back gives. The map is its own inverse: it needs no skid_map_from.
#[test]
fn tracks_that_run_opposite_ways_mirror_with_the_map_minus_one() {
    const L: f64 = 8000.0;
    let dir = tempfile::tempdir().unwrap();
    let samples = crate::support::root().join("samples");
    let profile = std::fs::read_to_string(samples.join("track/r2/profile.toml")).unwrap();
    let (head, knots) = profile.split_once("[[knot]]").unwrap();
    let numbers_in = |key: &str| -> Vec<f64> {
        let line = head.lines().find(|l| l.starts_with(key)).unwrap();
        numbers(line.split_once('=').unwrap().1)
    };
    let (origin, direction) = (numbers_in("origin"), numbers_in("direction"));
    let far: Vec<f64> = (0..3).map(|i| origin[i] + L * direction[i]).collect();
    let list = |v: &[f64]| {
        v.iter()
            .map(|x| format!("{x:.12}"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let head: String = head
        .lines()
        .filter(|l| !l.starts_with("data_sha256"))
        .map(|l| match l {
            l if l.starts_with("origin") => format!("origin = [{}]\n", list(&far)),
            l if l.starts_with("direction") => {
                let back: Vec<f64> = direction.iter().map(|d| -d).collect();
                format!("direction = [{}]\n", list(&back))
            }
            l => format!("{l}\n"),
        })
        .collect();
    // D'(s') = D(L − s'): the same deviation where the robot stands.
    let mut knots: Vec<(f64, String)> = format!("[[knot]]{knots}")
        .split("[[knot]]")
        .skip(1)
        .map(|k| {
            let skid = numbers(k.lines().nth(1).unwrap())[0];
            let k = k.replacen(
                &format!("skid = {skid:.1}"),
                &format!("skid = {:.1}", L - skid),
                1,
            );
            (L - skid, format!("[[knot]]{}\n", k.trim_end()))
        })
        .collect();
    knots.sort_by(|a, b| a.0.total_cmp(&b.0));
    let reversed = format!(
        "{head}{}",
        knots.iter().map(|k| k.1.as_str()).collect::<String>()
    );
    let profile_path = write(dir.path(), "r2_reversed.toml", &reversed);
    let base_far = format!(
        "base = {{ x = {:.3}, y = {:.3}, z = {:.3},",
        far[0], far[1], far[2]
    );
    let cell = write(
        dir.path(),
        "reversed.toml",
        &sample_cell_with("skid_map = [1.0, 0.0]", "skid_map = [-1.0, 8000.0]")
            .replace("base = { x = 0.000, y = -202.033, z = -0.720,", &base_far)
            .replace(
                "track_axis = [1.0, 0.0000003, 0.0000022]",
                "track_axis = [-1.0, -0.0000003, -0.0000022]",
            )
            .replace(
                &format!("\"{}\"", samples.join("track/r2/profile.toml").display()),
                &format!("\"{}\"", profile_path.display()),
            ),
    );
    let transfer = |input: &Path, cell: &Path, from: &str, to: &str, out: &str| {
        let out = dir.path().join(out);
        let (code, _, err) = transfer_mirrored_between(
            input,
            cell.to_str().unwrap(),
            from,
            to,
            &["-o", out.to_str().unwrap()],
        );
        assert_eq!(code, 0, "{err}");
        // The reversed profile reads as one `track fit` wrote: no warning about it.
        assert!(!err.contains("r2_reversed.toml"), "{err}");
        out
    };
    let spot_line = samples.join("rapid/spot_line.mod");
    let sample_cell = samples.join("cell.toml");
    let aligned = transfer(&spot_line, &sample_cell, "r1", "r2", "aligned.mod");
    let opposite = transfer(&spot_line, &cell, "r1", "r2", "opposite.mod");
    let read = |p: &Path| trackfix::syntax::latin1(&std::fs::read(p).unwrap());
    let (a, b) = (
        numbers_of_targets(&read(&aligned)),
        numbers_of_targets(&read(&opposite)),
    );
    assert_eq!(a.len(), 218);
    for ((name, a), (_, b)) in a.iter().zip(&b) {
        let skid = if a.len() > 12 { 11 } else { 6 };
        assert!(
            (b[skid] - (L - a[skid])).abs() < 1e-9,
            "{name}: {a:?} {b:?}"
        );
        let off = (0..skid).map(|i| (a[i] - b[i]).abs()).fold(0.0, f64::max);
        assert!(off <= 1e-4 + 1e-9, "{name}: {off}: {a:?} {b:?}");
    }
    let aligned_back = transfer(&aligned, &sample_cell, "r2", "r1", "aligned_back.mod");
    let opposite_back = transfer(&opposite, &cell, "r2", "r1", "opposite_back.mod");
    assert_eq!(read(&aligned_back), read(&opposite_back));
}

/// A module with a target in a work object turned by 5° about z (its plane then crosses the
/// tracks' mirror at 5°), one in world and one in a work object the program does not declare.
const WOBJS: &str = "MODULE Wobjs
  TASK PERS wobjdata wTurned:=[FALSE,TRUE,\"\",[[1500,-1850.75,600],[0.999048,0,0,0.043619]],[[0,0,0],[1,0,0,0]]];
  CONST robtarget pTurned:=[[100,200,50],[0,0,1,0],[0,0,0,0],[3000.0,9E9,9E9,9E9,9E9,9E9]];
  CONST robtarget pWorld:=[[1500,-2500,600],[0,0,1,0],[0,0,0,0],[3000.0,9E9,9E9,9E9,9E9,9E9]];
  CONST robtarget pElse:=[[100,-200,50],[0,0,1,0],[0,0,0,0],[3000.0,9E9,9E9,9E9,9E9,9E9]];
  PROC main()
    MoveL pTurned, v100, fine, tool0 \\WObj:=wTurned;
    MoveL pWorld, v100, fine, tool0;
    MoveL pElse, v100, fine, tool0 \\WObj:=wElse;
  ENDPROC
ENDMODULE
";

/// With the mirror plane in each target's work object (`frame_in = "wobj"`), the skid map is
/// checked in the plane of each work object the targets use, placed in the cell: the sample
/// cell's tracks (its map [1, 0]) are mirror images in world's xz plane, not in one turned by 5°,
/// whose image of r1's track runs 10° off r2's (the bases give the scale cos 10° = 0.984808).
/// A work object the cell cannot place (not declared) leaves its targets' map unchecked, said
/// in a warning. Before, with the plane in the work objects the map was never checked, and all
/// three targets were written, exit 0, without a word.
#[test]
fn a_skid_map_is_checked_in_the_plane_of_each_work_object() {
    let dir = tempfile::tempdir().unwrap();
    let cell = write(
        dir.path(),
        "per_wobj.toml",
        &rules_cell_with(&[
            (
                "frame = { x = 0.0, y = -1850.75, z = 0.0, rx = 0.0, ry = 0.0, rz = 0.0 }\n",
                "",
            ),
            ("frame_in = \"world\"\n", ""),
        ]),
    );
    let module = |skip: &str| -> String {
        WOBJS
            .lines()
            .filter(|l| skip.is_empty() || !l.contains(skip))
            .map(|l| format!("{l}\n"))
            .collect()
    };
    let run = |text: &str, command: &[&str]| {
        let input = write(dir.path(), "wobjs.mod", text);
        let mut args = vec![command[0], input.to_str().unwrap(), "--cell"];
        args.push(cell.to_str().unwrap());
        args.extend(&command[1..]);
        args.push("--diff");
        let (code, out, err) = trackfix(&args);
        (
            code,
            out,
            err.replace(dir.path().to_str().unwrap(), "<tmp>"),
        )
    };
    let transfer = ["transfer", "--from", "r1", "--to", "r2", "--mirror"];
    let mirror = ["mirror", "--robot", "r1", "--to", "r2"];
    for command in [&transfer[..], &mirror[..]] {
        let (code, out, err) = run(&module(""), command);
        assert_eq!(code, 2, "{command:?}: {err}");
        assert!(out.is_empty(), "{out}");
        let first = err.lines().next().unwrap();
        assert!(
            first.starts_with(
                "<tmp>/per_wobj.toml:50:12: error: skid map [1, 0] puts robot `r2`'s base "
            ) && first.contains(
                "from the mirror image of robot `r1`'s in the plane of work object `wTurned` at"
            ) && first.contains("the bases give [0.984808, "),
            "{command:?}: {first}"
        );
        assert!(
            err.contains("= help: write the map the bases give, or check both robots' base and track_axis and the mirror plane; or give the plane in world (frame_in = \"world\"), one plane for the targets of every work object"),
            "{err}"
        );
    }
    // Without the turned work object: world's plane fits; `mirror` writes pElse in wElse, for
    // which the map is not checked, and says so (a transfer refuses it: its `zero` needs wElse
    // in the cell as much).
    let (code, out, err) = run(&module("Turned"), &mirror);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("+  CONST robtarget pElse"), "{out}");
    assert_eq!(
        err.lines().find(|l| l.contains("not checked")),
        Some(
            "warning: <tmp>/wobjs.mod: skid map not checked for the targets of 1 work object(s) that place the mirror plane nowhere in the cell (with frame_in = \"wobj\" each target mirrors about the plane in its own work object): robtarget `pElse`: work object `wElse` is not declared in the program"
        ),
        "{err}"
    );
    let (code, _, err) = run(&module("Turned"), &transfer);
    assert_eq!(code, 3, "{err}");
    assert!(
        err.contains("work object `wElse` is not declared in the program")
            && !err.contains("not checked"),
        "{err}"
    );
}

/// `mirror --mirror-joints` without the arm's kinematics negates axes 1, 4 and 6: the joint
/// target's flange, and so its move in mm, is not known, and the summary says so with its
/// largest axis change (axis 4: 40° to −40°). Before: "largest move 0.000 mm / 0.0000°".
#[test]
fn mirror_summary_says_a_joint_targets_move_is_not_known_without_kinematics() {
    let (dir, stdout, err, text) = mirror_joint_target_alone(&["--plane", "xz"]);
    assert_eq!(
        literal(&text, "jT")[..6],
        [-5.0, 20.0, 10.0, -40.0, 60.0, 30.0]
    );
    let summary = format!("{stdout}{err}").replace(dir.path().to_str().unwrap(), "<tmp>");
    assert_eq!(
        summary.trim_end(),
        "<tmp>/joint.mod: 1 target(s) changed, 1 joint target(s) with axes changed by up to 80.0000° (their move in mm is not known without the arm's kinematics) → <tmp>/out.mod"
    );
}
