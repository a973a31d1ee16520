//! KUKA KRL: a `.src`/`.dat` pair per program (either loads both), bases, A/B/C angles,
//! Status and Turn.

use std::path::{Path, PathBuf};

use crate::kinematics::{ConfigValue, Joints, Kinematics};
use crate::output::InputBytes;
use crate::position::{Config, KindSpec, PositionKind, Program};
use crate::program::{LoadError, LoadOptions};
use crate::syntax::Edit;
use crate::transform::rewrite::bits_edit;

use super::{Dialect, Language, Vocabulary};

/// The KRL dialect.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Krl;

#[allow(non_upper_case_globals)]
impl Language {
    /// KUKA KRL (`.src`, `.dat`, `.sub`).
    pub const Krl: Language = Language::of(&Krl);
}

#[allow(non_upper_case_globals)]
impl PositionKind {
    /// KRL `E6POS`.
    pub const E6Pos: PositionKind = PositionKind::new(&KindSpec::pose("E6POS"));
    /// KRL `POS`.
    pub const Pos: PositionKind = PositionKind::new(&KindSpec::pose("POS"));
    /// KRL `FRAME` used as a motion target.
    pub const Frame: PositionKind = PositionKind::new(&KindSpec::pose("FRAME"));
    /// KRL `E6AXIS`.
    pub const E6Axis: PositionKind = PositionKind::new(&KindSpec::joints("E6AXIS"));
    /// KRL `AXIS`.
    pub const Axis: PositionKind = PositionKind::new(&KindSpec::joints("AXIS"));
}

/// Turn bits of A1, A4 and A6: a mirror-image robot runs those axes with the opposite sign.
const TURN_A1_A4_A6: u32 = 0b10_1001;

const VOCABULARY: Vocabulary = Vocabulary {
    frame_column: "base",
    frames: "bases",
    frame: "base",
    // A base on an external kinematic (a positioner) is `BASE_DATA[n]` with its
    // `MACHINE_FRAME_DAT[n]` naming the kinematic (`MACH_IDX`), or `$BASE = EK(…)`.
    moved_frame: "MACHINE_FRAME_DAT: an external kinematic",
    tool_kind: "tool",
    stationary_tool: "IPO_FRAME #TCP",
    stationary_point: "$IPO_MODE or its FDAT's IPO_FRAME is #TCP on some path to the motion, or may be",
    world_frames: &["base_data[0]", "$nullframe", "$world"],
    frame_of_a_motion: "set the base before each motion to it (BAS(#BASE,n), $BASE = BASE_DATA[n] or the point's FDAT), the same on every path",
};

fn extension(p: &Path) -> Option<String> {
    p.extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
}

impl Dialect for Krl {
    fn name(&self) -> &'static str {
        "krl"
    }

    fn extensions(&self) -> &'static [&'static str] {
        &["src", "dat", "sub"]
    }

    fn load(&self, path: &Path, options: &LoadOptions) -> Result<Program, LoadError> {
        crate::krl::load_program(path, options)
    }

    fn reparse(
        &self,
        files: Vec<(PathBuf, Vec<u8>)>,
        options: &LoadOptions,
    ) -> Result<Program, LoadError> {
        // A KSS tree's own `$config.dat` was read instead of the cell's when it was loaded: the
        // transformed tree is read again the same way, or its global points would vanish.
        let own_config = files.iter().any(|(p, _)| is_config_dat(p));
        crate::krl::load_program_from_sources(files, &tree_options(own_config, options))
    }

    /// A `.dat` whose `.src` is listed is dropped: loading the `.src` loads both. The `.dat` is
    /// found the way `krl::load_program` finds it (stem and extension in any case) and compared
    /// as a file, not as spelled (`./a.dat` is `a.dat`).
    fn dedupe_inputs(&self, inputs: &mut Vec<PathBuf>) {
        let same_file = |p: &Path| std::fs::canonicalize(p).unwrap_or_else(|_| p.to_owned());
        let stem_key = |p: &Path| {
            let stem = p
                .file_stem()
                .map(|s| s.to_string_lossy().to_ascii_lowercase());
            (same_file(p).parent().map(Path::to_owned), stem)
        };
        // Only a `.src` whose stem a listed `.dat` shares needs its directory read.
        let dat_stems: std::collections::BTreeSet<_> = inputs
            .iter()
            .filter(|p| extension(p).as_deref() == Some("dat"))
            .map(|p| stem_key(p))
            .collect();
        let partners: std::collections::BTreeSet<PathBuf> = inputs
            .iter()
            .filter(|p| extension(p).as_deref() == Some("src") && dat_stems.contains(&stem_key(p)))
            .filter_map(|p| crate::krl::partner_of(p))
            .map(|d| same_file(&d))
            .collect();
        inputs.retain(|p| {
            !(extension(p).as_deref() == Some("dat") && partners.contains(&same_file(p)))
        });
    }

    /// Modules named together from one folder are one program, as a KSS tree's `Program`
    /// folder is: a `GLOBAL` point or routine of one is the other's, where each pair resolved
    /// alone moved to another module's `GLOBAL` point in a base its own module never saw.
    fn joins_files_given_together(&self) -> bool {
        true
    }

    fn joins_given_files_per_folder(&self) -> bool {
        true
    }

    /// A KSS robot tree (`KRC/R1`): the nearest of the four folders above the file that holds a
    /// `Program` folder or `System/$config.dat`. Of `System/`, only `$config.dat` joins the
    /// program; the other system files (`$machine.dat`, …) stay files of their own.
    fn program_root(&self, path: &Path) -> Option<PathBuf> {
        let named = |p: &Path, n: &str| {
            p.file_name()
                .and_then(|x| x.to_str())
                .is_some_and(|x| x.eq_ignore_ascii_case(n))
        };
        let in_system = path.parent().is_some_and(|d| named(d, "System"));
        if in_system && !named(path, "$config.dat") {
            return None;
        }
        path.ancestors().skip(1).take(4).find_map(|dir| {
            let entries = std::fs::read_dir(dir).ok()?;
            let mut found = false;
            for e in entries.filter_map(Result::ok) {
                let p = e.path();
                if !e.file_type().is_ok_and(|t| t.is_dir()) {
                    continue;
                }
                if named(&p, "Program") {
                    found = true;
                } else if named(&p, "System") {
                    found |= std::fs::read_dir(&p).is_ok_and(|mut sys| {
                        sys.any(|f| f.is_ok_and(|f| named(&f.path(), "$config.dat")))
                    });
                }
            }
            found.then(|| dir.to_owned())
        })
    }

    /// Every `.src`/`.dat` pair of a robot tree with its own `$config.dat` (which then stands for
    /// the cell's), resolved together: a point or base declared in one file is seen from the
    /// others.
    fn load_together(
        &self,
        sources: Vec<(PathBuf, InputBytes)>,
        options: &LoadOptions,
    ) -> Result<Program, LoadError> {
        let same_file = |p: &Path| std::fs::canonicalize(p).unwrap_or_else(|_| p.to_owned());
        // Each file given with its partner after it, once, in that order, each path with the
        // file it names (found once); a partner given too is taken from the bytes read, the
        // others are read here.
        let mut all: Vec<(PathBuf, PathBuf)> = Vec::new();
        let mut given: Vec<(PathBuf, Option<InputBytes>)> = Vec::with_capacity(sources.len());
        for (p, bytes) in sources {
            let partner = crate::krl::partner_of(&p);
            let file = same_file(&p);
            given.push((file.clone(), Some(bytes)));
            all.push((p, file));
            all.extend(partner.map(|q| {
                let file = same_file(&q);
                (q, file)
            }));
        }
        let mut seen = std::collections::BTreeSet::new();
        all.retain(|(_, file)| seen.insert(file.clone()));
        let own_config = all.iter().any(|(p, _)| is_config_dat(p));
        let mut read = Vec::with_capacity(all.len());
        for (p, file) in all {
            let bytes = match given
                .iter_mut()
                .find(|(g, _)| *g == file)
                .and_then(|(_, b)| b.take())
            {
                Some(bytes) => bytes,
                None => crate::program::read_source(&p, options)?,
            };
            read.push((p, bytes));
        }
        crate::krl::load_program_from_sources(read, &tree_options(own_config, options))
    }

    fn vocabulary(&self) -> &'static Vocabulary {
        &VOCABULARY
    }

    fn pose_fields_left_out(&self, literal: &[u8]) -> Option<String> {
        const POSE: [u8; 6] = *b"XYZABC";
        let inner = trim_latin1(literal);
        let inner = inner
            .strip_prefix(b"{")
            .and_then(|i| i.strip_suffix(b"}"))
            .unwrap_or(inner);
        let mut written = [false; 6];
        let mut start = 0;
        while start <= inner.len() {
            let end = next_separator(inner, start);
            let field = trim_latin1_start(inner.get(start..end).unwrap_or_default());
            start = end + 1;
            if let [letter, b' ' | b'\t', ..] = field
                && let Some(k) = POSE.iter().position(|p| p.eq_ignore_ascii_case(letter))
                && let Some(w) = written.get_mut(k)
            {
                *w = true;
            }
        }
        // A literal of no pose field (joints, a frame's base data) is no partial pose.
        if written.iter().all(|&w| !w) || written.iter().all(|&w| w) {
            return None;
        }
        let left: Vec<String> = POSE
            .iter()
            .zip(written)
            .filter(|(_, w)| !w)
            .map(|(&p, _)| char::from(p).to_string())
            .collect();
        Some(left.join(", "))
    }

    fn implausible_configuration(&self, literal: &[u8]) -> Option<String> {
        // `{X …, S 6, T 'B010101', …}`: Status and Turn are small integers or binary strings.
        // Read on the bytes (every position of a check passes here): a byte is one character
        // of the Latin-1 text the message quotes.
        // Only a field whose name is the one letter S or T is read: one that does not start
        // so is stepped over to the next separator without being trimmed or split (this runs
        // for every target of a `check`, whose fields are mostly `X 1200.5`).
        let mut start = 0;
        while start <= literal.len() {
            // The fields `split` on the separators gives, the separators found eight bytes at
            // a time: a byte test each was most of the check.
            let end = next_separator(literal, start);
            let field = literal.get(start..end).unwrap_or_default();
            start = end + 1;
            let field = trim_latin1_start(field);
            let which = match field {
                [b'S' | b's', b' ' | b'\t', ..] => "Status",
                [b'T' | b't', b' ' | b'\t', ..] => "Turn",
                _ => continue,
            };
            let value = trim_latin1(&field[2..]);
            if value.is_empty() {
                // `S ` is the name alone, its space trimmed away: no value to read.
                continue;
            }
            let binary = value.len() > 3
                && value.starts_with(b"'")
                && value.ends_with(b"'")
                && matches!(value[1], b'B' | b'b');
            if !binary && !reads_as_u32(value) {
                return Some(format!(
                    "has {which} {}: Status and Turn are small whole numbers",
                    crate::syntax::latin1(value)
                ));
            }
        }
        None
    }

    fn names_follow_file(&self) -> bool {
        true
    }

    fn line_comment(&self) -> Option<&'static str> {
        Some(";")
    }

    fn header_keywords(&self) -> &'static [&'static str] {
        &["DEF", "DEFDAT", "DEFFCT", "GLOBAL DEF", "GLOBAL DEFFCT"]
    }

    fn axis_name(&self, index: usize) -> String {
        format!("E{}", index + 1)
    }

    /// KRL writes Status and Turn (`S 6, T 27`).
    fn configuration_of(&self, kin: &Kinematics, j: &Joints) -> ConfigValue {
        ConfigValue::status_turn_of(kin, j)
    }

    /// A mirror-image arm: the Turn bits of A1, A4 and A6 toggled; Status unchanged.
    fn mirror_config(&self, config: &Config) -> Vec<Edit> {
        let Config::StatusTurn { turn, .. } = config else {
            return Vec::new();
        };
        turn.as_ref()
            .and_then(|t| bits_edit(turn, t.value() ^ TURN_A1_A4_A6))
            .into_iter()
            .collect()
    }
}

/// Whether `path` names a `$config.dat` (in any case).
fn is_config_dat(path: &Path) -> bool {
    path.file_name()
        .and_then(|n| n.to_str())
        .is_some_and(|n| n.eq_ignore_ascii_case("$config.dat"))
}

/// A program that holds its own `$config.dat` (a KSS tree) uses it, not the cell's.
fn tree_options(own_config: bool, options: &LoadOptions) -> LoadOptions {
    if own_config {
        LoadOptions {
            krl_config_dat: None,
            ..options.clone()
        }
    } else {
        options.clone()
    }
}

/// `bytes` without the leading and trailing characters `str::trim` drops, each byte read as a
/// Latin-1 character (tab to carriage return, space, NEL, no-break space).
fn trim_latin1(bytes: &[u8]) -> &[u8] {
    let start = trim_latin1_start(bytes);
    let end = start
        .iter()
        .rposition(|b| !latin1_space(*b))
        .map_or(0, |e| e + 1);
    start.get(..end).unwrap_or(&[])
}

/// The place of the first `,`, `{` or `}` of `bytes` from `from` on, or the end: the words
/// of eight bytes are tested at once (the lowest byte a word flags is exact, which is the one
/// taken), the last few bytes one by one.
#[inline(always)]
fn next_separator(bytes: &[u8], from: usize) -> usize {
    const ONES: u64 = u64::from_le_bytes([0x01; 8]);
    const HIGH: u64 = u64::from_le_bytes([0x80; 8]);
    let zero_in = |v: u64| v.wrapping_sub(ONES) & !v & HIGH;
    let mut i = from;
    while let Some(word) = bytes.get(i..).and_then(|b| b.first_chunk::<8>()) {
        let x = u64::from_le_bytes(*word);
        let found = zero_in(x ^ (ONES * u64::from(b',')))
            | zero_in(x ^ (ONES * u64::from(b'{')))
            | zero_in(x ^ (ONES * u64::from(b'}')));
        if found != 0 {
            return i + (found.trailing_zeros() / 8) as usize;
        }
        i += 8;
    }
    while let Some(&b) = bytes.get(i) {
        if matches!(b, b',' | b'{' | b'}') {
            return i;
        }
        i += 1;
    }
    bytes.len()
}

/// What `str::trim_start` leaves of the Latin-1 text `bytes`.
fn trim_latin1_start(bytes: &[u8]) -> &[u8] {
    let start = bytes
        .iter()
        .position(|b| !latin1_space(*b))
        .unwrap_or(bytes.len());
    bytes.get(start..).unwrap_or(&[])
}

/// The bytes whose Latin-1 character is white space to `str::trim`.
fn latin1_space(b: u8) -> bool {
    matches!(b, 0x09..=0x0D | b' ' | 0x85 | 0xA0)
}

/// Whether `str::parse::<u32>` reads `text`: an optional `+`, then digits of a value that
/// fits 32 bits (any number of leading zeros). On the bytes: no UTF-8 check, no error built.
fn reads_as_u32(text: &[u8]) -> bool {
    let digits = text.strip_prefix(b"+").unwrap_or(text);
    !digits.is_empty()
        && digits
            .iter()
            .try_fold(0u32, |v, &b| {
                let d = b.wrapping_sub(b'0');
                (d <= 9).then_some(())?;
                v.checked_mul(10)?.checked_add(u32::from(d))
            })
            .is_some()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn files_loaded_together_take_the_bytes_given_and_read_only_their_partners() {
        let dir = tempfile::tempdir().unwrap();
        let src = dir.path().join("a.src");
        let dat = dir.path().join("a.dat");
        // On disk the .src differs from the bytes given: the given ones are what load_group
        // read, and they are parsed; the .dat, not given, is read from disk.
        std::fs::write(&src, b"DEF a()\nEND\n").unwrap();
        std::fs::write(
            &dat,
            b"DEFDAT a\nDECL E6POS XP1={X 1,Y 2,Z 3,A 0,B 0,C 0}\nENDDAT\n",
        )
        .unwrap();
        let given: &[u8] = b"DEF a()\nPTP XP1\nEND\n";
        let program = Krl
            .load_together(
                vec![(src.clone(), InputBytes::from(given.to_vec()))],
                &LoadOptions::default(),
            )
            .unwrap();
        let paths: Vec<&Path> = program.files.iter().map(|f| f.path.as_path()).collect();
        assert_eq!(paths, [src.as_path(), dat.as_path()]);
        assert_eq!(&*program.files[0].source, given);
        let xp1 = program.files[1].positions().next().unwrap();
        assert_eq!(&*xp1.usage.lines, &[2]);
    }

    /// The check as it was written on the Latin-1 text, for comparison.
    fn on_text(literal: &[u8]) -> Option<String> {
        let text = crate::syntax::latin1(literal);
        for field in text.split([',', '{', '}']) {
            let Some((name, value)) = field.trim().split_once([' ', '\t']) else {
                continue;
            };
            let which = match name.to_ascii_uppercase().as_str() {
                "S" => "Status",
                "T" => "Turn",
                _ => continue,
            };
            let value = value.trim();
            let binary = value.len() > 3
                && value.starts_with('\'')
                && value.ends_with('\'')
                && value.get(1..2).is_some_and(|b| b.eq_ignore_ascii_case("b"));
            if !binary && value.parse::<u32>().is_err() {
                return Some(format!(
                    "has {which} {value}: Status and Turn are small whole numbers"
                ));
            }
        }
        None
    }

    proptest! {
        // Short texts, cheap to check: enough cases to meet a field that is a name and spaces
        // only (`S ,`), which the default 256 can miss.
        #![proptest_config(ProptestConfig::with_cases(8192))]
        #[test]
        fn configuration_check_reads_bytes_as_the_text_check_did(
            parts in proptest::collection::vec(
                prop_oneof![
                    Just(b"S".to_vec()), Just(b"t".to_vec()), Just(b"X".to_vec()),
                    Just(b" ".to_vec()), Just(b"\t".to_vec()), Just(b",".to_vec()),
                    Just(b"{".to_vec()), Just(b"}".to_vec()), Just(b"'".to_vec()),
                    Just(b"B".to_vec()), Just(b"+".to_vec()), Just(vec![0x85]),
                    Just(vec![0xA0]), Just(vec![0x0B]), Just(vec![0xE9]), Just(vec![0x1C]),
                    "[0-9]{1,11}".prop_map(String::into_bytes),
                ],
                0..14,
            )
        ) {
            let literal = parts.concat();
            prop_assert_eq!(Krl.implausible_configuration(&literal), on_text(&literal));
        }
    }

    #[test]
    fn pose_fields_left_out_are_named_in_order() {
        let left = |t: &str| Krl.pose_fields_left_out(t.as_bytes());
        assert_eq!(left("{Z 500}").as_deref(), Some("X, Y, A, B, C"));
        assert_eq!(left("{ x 5,\ty 6 ,C 0}").as_deref(), Some("Z, A, B"));
        assert_eq!(left("{X 1,Y 2,Z 3,A 0,B 0,C 0,S 2,T 35,E1 100}"), None);
        // Fields that are no pose: joints, a configuration alone, external axes.
        assert_eq!(left("{A1 0,A2 -90,A3 90,A4 0,A5 0,A6 0}"), None);
        assert_eq!(left("{S 2,T 35}"), None);
        assert_eq!(left("{E1 100}"), None);
        // A name that only starts with a pose letter is no pose field.
        assert_eq!(left("{XX 1,Z 2}").as_deref(), Some("X, Y, A, B, C"));
    }

    proptest! {
        /// The separators found by words are the first one a byte-by-byte search finds.
        #[test]
        fn next_separator_is_the_first_one(
            bytes in proptest::collection::vec(prop_oneof![Just(b','), Just(b'{'), Just(b'}'), Just(b'+'), Just(b'-'), Just(0x2c ^ 0x80), Just(0xfb), Just(0x7d ^ 0x01), Just(0), any::<u8>()], 0..40),
            from in 0usize..45,
        ) {
            let from = from.min(bytes.len());
            let plain = bytes[from..]
                .iter()
                .position(|b| matches!(b, b',' | b'{' | b'}'))
                .map_or(bytes.len(), |i| from + i);
            prop_assert_eq!(next_separator(&bytes, from), plain);
        }
    }

    proptest! {
        /// The byte reading of a whole number is `str::parse::<u32>`'s.
        #[test]
        fn reads_as_u32_is_parse(text in "[+-]?[0-9]{0,12}|[0-9+ a]{0,4}") {
            prop_assert_eq!(reads_as_u32(text.as_bytes()), text.parse::<u32>().is_ok());
        }
    }

    #[test]
    fn reads_as_u32_at_the_edges() {
        for (text, ok) in [
            ("4294967295", true),
            ("4294967296", false),
            ("+0004294967295", true),
            ("+", false),
            ("", false),
            ("-0", false),
            ("++1", false),
        ] {
            assert_eq!(reads_as_u32(text.as_bytes()), ok, "{text}");
            assert_eq!(text.parse::<u32>().is_ok(), ok, "{text}");
        }
    }

    #[test]
    fn configuration_check_finds_what_it_should() {
        let check = |s: &str| Krl.implausible_configuration(s.as_bytes());
        assert_eq!(check("{X 1, S 6, T 'B010101'}"), None);
        assert_eq!(check("{S ,T \t}"), None);
        assert_eq!(
            check("{X 1, S 6, T 1e30}").as_deref(),
            Some("has Turn 1e30: Status and Turn are small whole numbers")
        );
        assert_eq!(
            check("{s\t 'b'x, T 2}").as_deref(),
            Some("has Status 'b'x: Status and Turn are small whole numbers")
        );
    }
}
