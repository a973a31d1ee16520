//! `profile.toml`: a fitted track profile and its evaluation `D(s)` (docs/design.md §3, §6).

use std::path::Path;
use std::sync::Arc;

use nalgebra::{Translation3, Vector3};
use serde::{Deserialize, Serialize};

use super::error::LocatedError;
use super::nominal::FitOptions;
use super::spline::{CubicSpline, EndCondition, SplineError};
use crate::geometry::{Pose, pose_xyz_deg, xyz_deg};
use crate::syntax::Span;

/// The format tag every profile file starts with.
pub const PROFILE_FORMAT: &str = "trackfix-profile/1";

pub use super::error::TrackError;

/// One sampling position's deviation `D_i` (mm, degrees; docs/design.md §2 `rx, ry, rz`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Knot {
    /// The commanded track position `s_i`, mm.
    pub skid: f64,
    /// Translation of the base frame from the nominal straight track, along the nominal's x, mm.
    pub dx: f64,
    /// Translation along base y, mm.
    pub dy: f64,
    /// Translation along base z, mm.
    pub dz: f64,
    /// Fixed-axis rotation about x, degrees (applied first: `Rz·Ry·Rx`).
    pub rx: f64,
    /// Rotation about base y, degrees.
    pub ry: f64,
    /// Rotation about base z, degrees.
    pub rz: f64,
    /// Standard uncertainty (k = 1) of `dx` from the identification noise, mm; absent in
    /// profiles fitted without measurements, and in old profiles (likewise the five below).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub u_dx: Option<f64>,
    /// Of `dy`, mm.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub u_dy: Option<f64>,
    /// Of `dz`, mm.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub u_dz: Option<f64>,
    /// Of `rx`, degrees.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub u_rx: Option<f64>,
    /// Of `ry`, degrees.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub u_ry: Option<f64>,
    /// Of `rz`, degrees.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub u_rz: Option<f64>,
    /// The centroid of the points the knot's frame was identified from (base frame, mm):
    /// there a position error does not correlate with the rotation error.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub u_centre: Option<[f64; 3]>,
    /// Standard uncertainties (k = 1) of a point at `u_centre` along the base axes, mm.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub u_centre_xyz: Option<[f64; 3]>,
}

/// A knot's standard uncertainties (k = 1) from the identification of its frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KnotUncertainty {
    /// `[u_dx, u_dy, u_dz, u_rx, u_ry, u_rz]`, mm and degrees.
    pub u: [f64; 6],
    /// Centroid of the identification points, base frame, mm.
    pub centre: [f64; 3],
    /// Standard uncertainties of a point at `centre`, mm.
    pub centre_xyz: [f64; 3],
}

impl Knot {
    /// `[dx, dy, dz, rx, ry, rz]`.
    pub fn components(&self) -> [f64; 6] {
        [self.dx, self.dy, self.dz, self.rx, self.ry, self.rz]
    }

    /// A knot of `[dx, dy, dz, rx, ry, rz]` at `skid`.
    pub fn from_components(skid: f64, [dx, dy, dz, rx, ry, rz]: [f64; 6]) -> Knot {
        Knot {
            skid,
            dx,
            dy,
            dz,
            rx,
            ry,
            rz,
            u_dx: None,
            u_dy: None,
            u_dz: None,
            u_rx: None,
            u_ry: None,
            u_rz: None,
            u_centre: None,
            u_centre_xyz: None,
        }
    }

    /// `(u_centre, u_centre_xyz)` if the knot carries both.
    pub fn centre_uncertainty(&self) -> Option<([f64; 3], [f64; 3])> {
        Some((self.u_centre?, self.u_centre_xyz?))
    }

    /// `[u_dx, u_dy, u_dz, u_rx, u_ry, u_rz]` if the knot carries all six.
    pub fn uncertainty(&self) -> Option<[f64; 6]> {
        Some([
            self.u_dx?, self.u_dy?, self.u_dz?, self.u_rx?, self.u_ry?, self.u_rz?,
        ])
    }

    /// The same knot with standard uncertainties `[u_dx, …, u_rz]` (`None` removes them).
    pub fn with_uncertainty(mut self, u: Option<[f64; 6]>) -> Knot {
        let [a, b, c, d, e, f] = match u {
            Some(u) => u.map(Some),
            None => [None; 6],
        };
        (self.u_dx, self.u_dy, self.u_dz) = (a, b, c);
        (self.u_rx, self.u_ry, self.u_rz) = (d, e, f);
        self
    }

    /// A knot of no deviation at `skid`.
    pub fn zero(skid: f64) -> Knot {
        Knot::from_components(skid, [0.0; 6])
    }

    /// The knot's pose `D_i`.
    pub fn pose(&self) -> Pose {
        pose_xyz_deg(self.dx, self.dy, self.dz, self.rx, self.ry, self.rz)
    }
}

/// What `D(s)` does outside `[s_0, s_N]` (docs/design.md §3).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Extrapolate {
    /// Refuse a skid outside the measured range.
    Error,
    /// Hold the deviation of the nearest end.
    Clamp,
    /// Continue the deviation along its slope at the nearest end.
    Linear,
}

/// Which straight line the deviations are taken from (docs/design.md §3).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Reference {
    /// Least-squares line of the origins, mean rotation.
    Regression,
    /// The first sampling frame.
    First,
}

/// Whether the gear factor's drift stays in the profile (docs/design.md §3).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
pub enum Gear {
    /// Keep the controller's gear ratio; its drift stays in the profile.
    #[serde(rename = "as-is")]
    #[value(name = "as-is")]
    AsIs,
    /// You enter the new gear ratio in the controller; the drift is taken out of the profile.
    #[serde(rename = "recalibrated")]
    Recalibrated,
}

/// The frame the tracker measured in, as far as the profile knows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum MeasuredIn {
    /// The cell's world frame (the tracker was aligned to the cell): the nominal can be
    /// compared with the cell's base and track axis.
    World,
    /// The tracker's own frame: only the frame-independent track direction in the robot base
    /// can be compared with a cell.
    Tracker,
}

/// Fewest knots whose spline can show the track's shape between them ([`Profile::measurement_warnings`]):
/// with three, it bends at most once over the whole track.
pub const FEW_KNOTS: usize = 4;

/// The shortest skid range a profile is taken to measure a track over without a word: a
/// linear track travels metres, so a shorter one was most likely written in metres.
pub const SHORT_TRACK_MM: f64 = 100.0;

/// How close to a multiple of π/2 a nominal's angle (degrees) must be for
/// [`Profile::measurement_warnings`] to take it for radians.
pub const RADIANS_TOLERANCE: f64 = 0.002;

/// The widest knot spacing the uncertainty between knots was calibrated for (500-1333 mm,
/// docs/design.md §14), rounded up: wider, [`Profile::measurement_warnings`] says what it misses.
pub const WIDE_KNOT_GAP_MM: f64 = 2000.0;

/// The controller's straight track `N(s) = (R_N, origin + s·step)` in the measurement frame.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Nominal {
    /// `p_0`, mm.
    pub origin: [f64; 3],
    /// Unit track axis `u`.
    pub direction: [f64; 3],
    /// `R_N` as `[rx, ry, rz]` degrees.
    pub rotation: [f64; 3],
    /// `g = |m|`: measured mm per commanded mm (thesis eq. 4.4).
    pub gear_factor: f64,
}

impl Nominal {
    /// The identity track: along x from the origin, gear factor 1.
    pub fn identity() -> Nominal {
        Nominal {
            origin: [0.0; 3],
            direction: [1.0, 0.0, 0.0],
            rotation: [0.0; 3],
            gear_factor: 1.0,
        }
    }
}

/// Figures of the fitted deviations, for reports (not used by `D(s)`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ProfileStats {
    /// Number of knots.
    pub knots: usize,
    /// RMS over the knots of `|(dx, dy, dz)|`, mm.
    pub position_rms_mm: f64,
    /// Largest `|(dx, dy, dz)|`, mm.
    pub position_max_mm: f64,
    /// Largest rotation angle of a knot, degrees.
    pub rotation_max_deg: f64,
    /// Peak-to-peak of the sideways deviation (horizontal, across the track) about its own
    /// straight line, mm.
    pub straightness_sideways_mm: f64,
    /// Peak-to-peak of the vertical deviation (base z) about its own straight line, mm.
    pub straightness_vertical_mm: f64,
    /// Peak-to-peak of the rotation about the track axis (twist), degrees.
    pub twist_deg: f64,
    /// sha256 of what `D(s)` is made of (reference, gear, nominal, knots; see
    /// [`Profile::data_sha256`]): a hand edit that changes them shows.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub data_sha256: Option<String>,
}

/// The on-disk layout, field order = file order.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct ProfileFile {
    format: String,
    name: String,
    /// sha256 of the frames file the profile was fitted from (empty when built in code).
    source_sha256: String,
    reference: Reference,
    gear: Gear,
    extrapolate: Extrapolate,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    measured_in: Option<MeasuredIn>,
    nominal: Nominal,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    stats: Option<ProfileStats>,
    knot: Vec<Knot>,
}

/// A fitted track profile: the nominal straight track and six natural cubic splines of the
/// deviation (docs/design.md §3).
#[derive(Clone, Debug)]
pub struct Profile {
    file: ProfileFile,
    /// dx, dy, dz, rx, ry, rz over skid.
    splines: [CubicSpline; 6],
}

impl PartialEq for Profile {
    fn eq(&self, other: &Profile) -> bool {
        self.file == other.file
    }
}

/// The span of the line `key = …` in the table `table` (`None`: the top level; `Some((header,
/// n))`: the `n`-th (0-based) table whose header line is `header`) of profile text.
fn key_span(text: &str, table: Option<(&str, usize)>, key: &str) -> Option<Span> {
    let mut offset = 0;
    let mut current: Option<(&str, usize)> = None;
    let mut seen: Vec<(&str, usize)> = Vec::new();
    for line in text.split_inclusive('\n') {
        let start = offset;
        offset += line.len();
        let trimmed = line.trim();
        if trimmed.starts_with('[') {
            let n = seen.iter().filter(|(h, _)| *h == trimmed).count();
            seen.push((trimmed, n));
            current = Some((trimmed, n));
        } else if current == table
            && trimmed
                .strip_prefix(key)
                .is_some_and(|rest| rest.trim_start().starts_with('='))
        {
            let lead = line.len() - line.trim_start().len();
            return Some(Span::new(start + lead, start + lead + trimmed.len()));
        }
    }
    None
}

/// The span of the `n`-th (0-based) `[[knot]]` header line.
fn knot_header_span(text: &str, n: usize) -> Option<Span> {
    let mut offset = 0;
    let mut count = 0;
    for line in text.split_inclusive('\n') {
        let start = offset;
        offset += line.len();
        if line.trim() == "[[knot]]" {
            if count == n {
                let lead = line.len() - line.trim_start().len();
                return Some(Span::new(start + lead, start + lead + 8));
            }
            count += 1;
        }
    }
    None
}

/// Whether text claims to be a profile: a `format = "trackfix-profile…"` line. Errors in a file
/// that does not are reported without quoting it (it may be anything, `/etc/passwd` included).
fn claims_to_be_a_profile(text: &str) -> bool {
    text.lines().any(|l| {
        l.trim_start().strip_prefix("format").is_some_and(|rest| {
            rest.trim_start().starts_with('=') && rest.contains("trackfix-profile")
        })
    })
}

/// The first knot value among the uncertainty keys that is no uncertainty: not finite, or
/// negative for a standard uncertainty (`u_centre`, a position, only has to be finite).
fn bad_uncertainty(knots: &[Knot]) -> Option<(usize, &'static str, f64)> {
    knots.iter().enumerate().find_map(|(i, k)| {
        let spreads = [
            ("u_dx", k.u_dx),
            ("u_dy", k.u_dy),
            ("u_dz", k.u_dz),
            ("u_rx", k.u_rx),
            ("u_ry", k.u_ry),
            ("u_rz", k.u_rz),
        ]
        .into_iter()
        .chain(
            k.u_centre_xyz
                .into_iter()
                .flatten()
                .map(|v| ("u_centre_xyz", Some(v))),
        )
        .filter_map(|(key, v)| Some((key, v?)))
        .find(|(_, v)| !v.is_finite() || *v < 0.0);
        let centre = k
            .u_centre
            .into_iter()
            .flatten()
            .map(|v| ("u_centre", v))
            .find(|(_, v)| !v.is_finite());
        spreads.or(centre).map(|(key, v)| (i, key, v))
    })
}

const PROFILE_HINT: &str =
    "a profile is what `trackfix track fit` writes; see samples/track/profile.toml for its keys";

impl Profile {
    /// A profile from knots alone: identity nominal, reference `regression`, gear `as-is`.
    pub fn from_knots(
        name: impl Into<String>,
        knots: Vec<Knot>,
        extrapolate: Extrapolate,
    ) -> Result<Profile, TrackError> {
        let opts = FitOptions {
            name: name.into(),
            extrapolate,
            ..FitOptions::default()
        };
        Profile::from_parts(&opts, Nominal::identity(), knots)
    }

    /// A profile with the name, reference, gear, extrapolation and source hash of `opts`;
    /// statistics are computed from the knots.
    pub fn from_parts(
        opts: &FitOptions,
        nominal: Nominal,
        knots: Vec<Knot>,
    ) -> Result<Profile, TrackError> {
        let splines = build_splines(&knots).map_err(|error| TrackError::Knots {
            context: format!("profile `{}`", opts.name),
            error,
        })?;
        let mut file = ProfileFile {
            format: PROFILE_FORMAT.to_string(),
            name: opts.name.clone(),
            source_sha256: opts.source_sha256.clone(),
            reference: opts.reference,
            gear: opts.gear,
            extrapolate: opts.extrapolate,
            measured_in: None,
            nominal,
            stats: None,
            knot: knots,
        };
        let mut stats = compute_stats(&file.knot, &file.nominal);
        stats.data_sha256 = Some(data_sha256(&file));
        file.stats = Some(stats);
        Ok(Profile { file, splines })
    }

    /// Reads and validates a `profile.toml`: unknown keys are an error, a missing key names
    /// itself, errors carry the file, line and column.
    pub fn load(path: &Path) -> Result<Profile, TrackError> {
        let bytes = crate::output::read_input(path).map_err(|error| TrackError::Io {
            path: path.to_path_buf(),
            error,
        })?;
        Profile::from_toml_bytes(&bytes, path)
    }

    /// Parses profile text; `path` is only used in messages.
    pub fn from_toml_str(text: &str, path: &Path) -> Result<Profile, TrackError> {
        Profile::from_toml_bytes(text.as_bytes(), path)
    }

    fn from_toml_bytes(bytes: &[u8], path: &Path) -> Result<Profile, TrackError> {
        let source: Arc<[u8]> = Arc::from(bytes);
        let located = |span: Span, message: String, hint: &str| {
            LocatedError::new(path, source.clone(), span, message, hint).in_utf8()
        };
        let not_a_profile = |at: usize| -> TrackError {
            located(
                Span::new(at, at),
                format!("not a trackfix profile: it has no `format = \"{PROFILE_FORMAT}\"` line"),
                PROFILE_HINT,
            )
            .without_quote()
            .into()
        };
        let text = std::str::from_utf8(bytes).map_err(|e| not_a_profile(e.valid_up_to()))?;
        if !claims_to_be_a_profile(text) {
            return Err(not_a_profile(0));
        }
        let file: ProfileFile = toml::from_str(text).map_err(|e| {
            located(
                e.span().map(Span::from).unwrap_or_default(),
                e.message().trim().to_owned(),
                PROFILE_HINT,
            )
        })?;
        if file.format != PROFILE_FORMAT {
            let span = key_span(text, None, "format").unwrap_or_default();
            return Err(located(
                span,
                format!(
                    "format = {:?}: this version of trackfix reads {PROFILE_FORMAT:?}",
                    file.format
                ),
                "fit the profile again with this version of trackfix, or use the version that wrote it",
            )
            .into());
        }
        if let Some((index, key, value)) = bad_uncertainty(&file.knot) {
            let span = key_span(text, Some(("[[knot]]", index)), key)
                .or_else(|| knot_header_span(text, index));
            return Err(located(
                span.unwrap_or_default(),
                format!(
                    "[[knot]] {}: {key} = {value}: an uncertainty is a finite number, 0 or more",
                    index + 1
                ),
                "fit the profile again from its measurements, or remove the knot's u_* keys",
            )
            .into());
        }
        let splines = build_splines(&file.knot).map_err(|error| {
            let span = match error {
                SplineError::NotIncreasing { index, .. } | SplineError::NotFinite { index } => {
                    key_span(text, Some(("[[knot]]", index)), "skid")
                        .or_else(|| knot_header_span(text, index))
                }
                _ => knot_header_span(text, 0).or_else(|| key_span(text, None, "format")),
            };
            TrackError::from(located(
                span.unwrap_or_default(),
                format!("[[knot]]: {error}"),
                "keep one [[knot]] per skid position, at least 2, in increasing skid order",
            ))
        })?;
        Ok(Profile { file, splines })
    }

    /// The profile as TOML text (what [`Profile::save`] writes).
    pub fn to_toml_string(&self) -> Result<String, TrackError> {
        let body = toml::to_string(&self.file)
            .map_err(|e| TrackError::Output(format!("cannot write the profile: {e}")))?;
        Ok(format!(
            "# trackfix track profile: deviation D(s) of the real robot base from the nominal \
             straight track,\n# mm and degrees (R = Rz*Ry*Rx), natural cubic splines through the \
             knots.\n{body}"
        ))
    }

    /// Writes the profile atomically.
    pub fn save(&self, path: &Path) -> Result<(), TrackError> {
        let text = self.to_toml_string()?;
        Ok(crate::output::write_file(path, text.as_bytes())?)
    }

    /// `[s_0, s_N]`.
    pub fn skid_range(&self) -> (f64, f64) {
        self.splines[0].range()
    }

    /// The profile's name.
    pub fn name(&self) -> &str {
        &self.file.name
    }

    /// sha256 (hex) of the frames file it was fitted from; empty if built in code.
    pub fn source_sha256(&self) -> &str {
        &self.file.source_sha256
    }

    /// The knots `D_i`.
    pub fn knots(&self) -> &[Knot] {
        &self.file.knot
    }

    /// The controller's straight track.
    pub fn nominal(&self) -> &Nominal {
        &self.file.nominal
    }

    /// Which straight line the deviations were taken from.
    pub fn reference(&self) -> Reference {
        self.file.reference
    }

    /// Whether the gear factor's drift is in the deviations or in the nominal.
    pub fn gear(&self) -> Gear {
        self.file.gear
    }

    /// What `D(s)` does outside the measured skid range.
    pub fn extrapolate(&self) -> Extrapolate {
        self.file.extrapolate
    }

    /// Fit statistics, if the file has them.
    pub fn stats(&self) -> Option<&ProfileStats> {
        self.file.stats.as_ref()
    }

    /// The six component splines `dx, dy, dz, rx, ry, rz`.
    pub fn splines(&self) -> &[CubicSpline; 6] {
        &self.splines
    }

    /// Same profile with standard uncertainties on its knots, one per knot in knot order
    /// (rounded to 1e-6 like the knots, the centre to 0.1 mm).
    pub fn with_knot_uncertainties(mut self, u: &[KnotUncertainty]) -> Result<Profile, TrackError> {
        if u.len() != self.file.knot.len() {
            return Err(TrackError::KnotUncertaintyCount {
                given: u.len(),
                knots: self.file.knot.len(),
            });
        }
        let r6 = |v: f64| (v * 1e6).round() / 1e6;
        for (k, u) in self.file.knot.iter_mut().zip(u) {
            *k = k.with_uncertainty(Some(u.u.map(r6)));
            k.u_centre = Some(u.centre.map(|v| (v * 10.0).round() / 10.0));
            k.u_centre_xyz = Some(u.centre_xyz.map(r6));
        }
        Ok(self)
    }

    /// The frame the profile was measured in, if it says.
    pub fn measured_in(&self) -> Option<MeasuredIn> {
        self.file.measured_in
    }

    /// Same profile, recording the frame it was measured in.
    pub fn with_measured_in(mut self, frame: MeasuredIn) -> Profile {
        self.file.measured_in = Some(frame);
        self
    }

    /// sha256 (hex) of what `D(s)` and `N(s)` are made of: reference, gear, the nominal and the
    /// knots' skid and six components (not the name, the extrapolation rule or other keys, which
    /// may be edited by hand).
    pub fn data_sha256(&self) -> String {
        data_sha256(&self.file)
    }

    /// What the profile's measurements cannot show, or were most likely written in other units
    /// than they are read in: fewer than [`FEW_KNOTS`] knots, or knots more than
    /// [`WIDE_KNOT_GAP_MM`] apart; skids over less than [`SHORT_TRACK_MM`] (metres); a nominal
    /// turned by a quarter turn's value in radians (`rz` 1.5708: radians read as degrees). Between such knots the spline is nearly a straight line
    /// whatever the track does there, and the uncertainty between knots (a leave-one-out
    /// estimate, `track::uncertainty`) sees nothing it missed: a sag or waviness there is in
    /// neither the deviation nor its `u`.
    pub fn measurement_warnings(&self) -> Vec<String> {
        let skids: Vec<f64> = self.file.knot.iter().map(|k| k.skid).collect();
        let gap = skids.windows(2).map(|w| w[1] - w[0]).fold(0.0, f64::max);
        let n = skids.len();
        let mut out = Vec::new();
        let (s0, s1) = self.skid_range();
        if n >= 2 && s1 - s0 < SHORT_TRACK_MM {
            out.push(format!(
                "profile `{}`: its skids span {s0} .. {s1} mm, shorter than {SHORT_TRACK_MM} mm: skids are read in mm (were they written in metres?)",
                self.file.name
            ));
        }
        // A base turned by 1.5708° or 3.1416° about an axis is a quarter or half turn written
        // in radians; degrees spelled so are not a turn anyone sets a base to.
        let [rx, ry, rz] = self.file.nominal.rotation;
        for (axis, v) in [("rx", rx), ("ry", ry), ("rz", rz)] {
            let quarter = std::f64::consts::FRAC_PI_2;
            let k = (v / quarter).round();
            if k != 0.0 && k.abs() <= 4.0 && (v - k * quarter).abs() < RADIANS_TOLERANCE {
                out.push(format!(
                    "profile `{}`: its nominal's {axis} is {v:.4}°, within {RADIANS_TOLERANCE} of {k}·π/2: angles are read in degrees (were they written in radians?)",
                    self.file.name
                ));
            }
        }
        if n < FEW_KNOTS {
            out.push(format!(
                "profile `{}`: {n} knots: the deviation between them is not measured (a sag or waviness there shows neither in D(s) nor in its uncertainty); measure at least every {WIDE_KNOT_GAP_MM} mm, or as densely as a scan's spectrum recommends",
                self.file.name
            ));
        } else if gap > WIDE_KNOT_GAP_MM {
            out.push(format!(
                "profile `{}`: knots up to {gap:.0} mm apart: a waviness shorter than {:.0} mm between them shows neither in D(s) nor in its uncertainty; measure at least every {WIDE_KNOT_GAP_MM} mm, or as densely as a scan's spectrum recommends",
                self.file.name,
                2.0 * gap
            ));
        }
        out
    }

    /// Where the file disagrees with itself: its `[stats]` are not those of its knots, or the
    /// knots or nominal changed since it was written (a hand edit). Empty for a consistent
    /// profile and for one without `[stats]`.
    pub fn consistency_warnings(&self) -> Vec<String> {
        let Some(written) = &self.file.stats else {
            return Vec::new();
        };
        let mut warnings = Vec::new();
        if let Some(hash) = &written.data_sha256
            && *hash != self.data_sha256()
        {
            warnings.push(format!(
                "profile `{}`: its knots or nominal changed after it was written ([stats] data_sha256 does not match); fit it again from its frames",
                self.file.name
            ));
        }
        let mut actual = compute_stats(&self.file.knot, &self.file.nominal);
        actual.data_sha256 = written.data_sha256.clone();
        let close = |a: f64, b: f64| (a - b).abs() <= 2e-6 * (1.0 + a.abs().max(b.abs()));
        let same = actual.knots == written.knots
            && [
                (actual.position_rms_mm, written.position_rms_mm),
                (actual.position_max_mm, written.position_max_mm),
                (actual.rotation_max_deg, written.rotation_max_deg),
                (
                    actual.straightness_sideways_mm,
                    written.straightness_sideways_mm,
                ),
                (
                    actual.straightness_vertical_mm,
                    written.straightness_vertical_mm,
                ),
                (actual.twist_deg, written.twist_deg),
            ]
            .iter()
            .all(|(a, b)| close(*a, *b));
        if !same {
            warnings.push(format!(
                "profile `{}`: its [stats] are not those of its knots (e.g. {} knots, position max {:.4} mm; the file says {} and {:.4} mm): it was edited by hand",
                self.file.name,
                actual.knots,
                actual.position_max_mm,
                written.knots,
                written.position_max_mm
            ));
        }
        warnings
    }

    /// Same profile, another extrapolation rule.
    pub fn with_extrapolate(mut self, extrapolate: Extrapolate) -> Profile {
        self.file.extrapolate = extrapolate;
        self
    }

    /// `[dx, dy, dz, rx, ry, rz]` of `D(s)` (mm, degrees), honouring `extrapolate`.
    pub fn deviation_components(&self, skid: f64) -> Result<[f64; 6], TrackError> {
        let (min, max) = self.skid_range();
        if !skid.is_finite() {
            return Err(TrackError::OutOfRange { skid, min, max });
        }
        // A skid written with fewer decimals than the knots must not fall off the end.
        let tol = 1e-9 * (1.0 + min.abs().max(max.abs()));
        let inside = skid >= min - tol && skid <= max + tol;
        // By reference: cloning the six splines (their knot vectors) per target was most of the
        // cost of `correct` outside parsing.
        // The six splines share their knots (`build_splines`): one search finds the interval
        // for all six, where each spline searched the knots again.
        let eval = |s: f64| {
            let i = self.splines[0].interval(s);
            // By a loop, not `each_ref().map`: through its closure each value was a call.
            let mut out = [0.0; 6];
            for (o, sp) in out.iter_mut().zip(&self.splines) {
                *o = sp.value_in(i, s);
            }
            out
        };
        if inside {
            return Ok(eval(skid.clamp(min, max)));
        }
        match self.file.extrapolate {
            Extrapolate::Error => Err(TrackError::OutOfRange { skid, min, max }),
            Extrapolate::Clamp => Ok(eval(skid.clamp(min, max))),
            Extrapolate::Linear => {
                let end = skid.clamp(min, max);
                let mut out = [0.0; 6];
                for (o, sp) in out.iter_mut().zip(&self.splines) {
                    *o = sp.value(end) + sp.derivative(end) * (skid - end);
                }
                Ok(out)
            }
        }
    }

    /// `D(s)`: the deviation of the real base from the nominal at skid `s`, in the nominal base
    /// frame (docs/design.md §3). Outside the range per the profile's `extrapolate` setting.
    pub fn deviation(&self, skid: f64) -> Result<Pose, TrackError> {
        let [dx, dy, dz, rx, ry, rz] = self.deviation_components(skid)?;
        Ok(pose_xyz_deg(dx, dy, dz, rx, ry, rz))
    }

    /// `N(s)`: the nominal base frame in the measurement frame (docs/design.md §3); with gear
    /// `recalibrated` the step per commanded mm is `g·u`, else `u`.
    pub fn nominal_frame(&self, skid: f64) -> Pose {
        let n = &self.file.nominal;
        let u = Vector3::from(n.direction);
        let step = match self.file.gear {
            Gear::AsIs => u,
            Gear::Recalibrated => u * n.gear_factor,
        };
        let p = Vector3::from(n.origin) + step * skid;
        let [rx, ry, rz] = n.rotation;
        Pose::from_parts(Translation3::from(p), xyz_deg(rx, ry, rz))
    }

    /// `N(s)·D(s)`: the modelled real base frame in the measurement frame.
    pub fn base_frame(&self, skid: f64) -> Result<Pose, TrackError> {
        Ok(self.nominal_frame(skid) * self.deviation(skid)?)
    }
}

fn data_sha256(file: &ProfileFile) -> String {
    use std::fmt::Write as _;
    // `{:?}` of f64 is the shortest text that reads back to the same number, as TOML writes it.
    let mut text = format!("{:?} {:?} {:?}\n", file.reference, file.gear, file.nominal);
    for k in &file.knot {
        let _ = writeln!(text, "{:?} {:?}", k.skid, k.components());
    }
    crate::digest::sha256_hex(text.as_bytes())
}

fn build_splines(knots: &[Knot]) -> Result<[CubicSpline; 6], SplineError> {
    let xs: Vec<f64> = knots.iter().map(|k| k.skid).collect();
    let comp = |i: usize| -> Result<CubicSpline, SplineError> {
        let ys: Vec<f64> = knots
            .iter()
            .map(|k| k.components().get(i).copied().unwrap_or(0.0))
            .collect();
        CubicSpline::new(&xs, &ys, EndCondition::Natural)
    };
    Ok([comp(0)?, comp(1)?, comp(2)?, comp(3)?, comp(4)?, comp(5)?])
}

/// Least-squares line `y ≈ a + b·x`: `(intercept, slope)`; a single x gives a flat line.
pub fn line_fit(x: &[f64], y: &[f64]) -> (f64, f64) {
    let n = x.len().min(y.len()) as f64;
    if n == 0.0 {
        return (0.0, 0.0);
    }
    let mx = x.iter().sum::<f64>() / n;
    let my = y.iter().sum::<f64>() / n;
    let sxx: f64 = x.iter().map(|v| (v - mx) * (v - mx)).sum();
    let sxy: f64 = x.iter().zip(y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let slope = if sxx > 0.0 { sxy / sxx } else { 0.0 };
    (my - slope * mx, slope)
}

/// `y_i - (a + b·x_i)` for the least-squares line.
pub fn line_residuals(x: &[f64], y: &[f64]) -> Vec<f64> {
    let (a, b) = line_fit(x, y);
    x.iter().zip(y).map(|(xi, yi)| yi - (a + b * xi)).collect()
}

fn peak_to_peak(v: &[f64]) -> f64 {
    let max = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let min = v.iter().copied().fold(f64::INFINITY, f64::min);
    if v.is_empty() { 0.0 } else { max - min }
}

impl Nominal {
    /// The unit track axis in the nominal robot base frame (`R_Nᵀ·u`); base x if degenerate.
    pub fn axis_in_base(&self) -> Vector3<f64> {
        let [rx, ry, rz] = self.rotation;
        (xyz_deg(rx, ry, rz).inverse() * Vector3::from(self.direction))
            .try_normalize(1e-12)
            .unwrap_or_else(Vector3::x)
    }
}

/// Statistics in track coordinates: along the axis, sideways (`z × axis`), vertical (base z).
fn compute_stats(knots: &[Knot], nominal: &Nominal) -> ProfileStats {
    let axis = nominal.axis_in_base();
    let sideways = Vector3::z()
        .cross(&axis)
        .try_normalize(1e-9)
        .unwrap_or_else(Vector3::y);
    let n = knots.len().max(1) as f64;
    let pos: Vec<Vector3<f64>> = knots
        .iter()
        .map(|k| Vector3::new(k.dx, k.dy, k.dz))
        .collect();
    let skids: Vec<f64> = knots.iter().map(|k| k.skid).collect();
    let side: Vec<f64> = pos.iter().map(|p| p.dot(&sideways)).collect();
    let vert: Vec<f64> = pos.iter().map(|p| p.z).collect();
    let twist: Vec<f64> = knots
        .iter()
        .map(|k| k.pose().rotation.scaled_axis().dot(&axis).to_degrees())
        .collect();
    let round = |v: f64| (v * 1e6).round() / 1e6;
    ProfileStats {
        knots: knots.len(),
        position_rms_mm: round((pos.iter().map(|p| p.norm_squared()).sum::<f64>() / n).sqrt()),
        position_max_mm: round(pos.iter().map(|p| p.norm()).fold(0.0, f64::max)),
        rotation_max_deg: round(
            knots
                .iter()
                .map(|k| k.pose().rotation.angle().to_degrees())
                .fold(0.0, f64::max),
        ),
        straightness_sideways_mm: round(peak_to_peak(&line_residuals(&skids, &side))),
        straightness_vertical_mm: round(peak_to_peak(&line_residuals(&skids, &vert))),
        twist_deg: round(peak_to_peak(&twist)),
        data_sha256: None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn knot(skid: f64, dz: f64, rx: f64) -> Knot {
        Knot::from_components(skid, [0.0, 0.0, dz, rx, 0.0, 0.0])
    }

    fn sample() -> Profile {
        Profile::from_knots(
            "t",
            vec![
                knot(0.0, 0.0, 0.0),
                knot(1000.0, -1.0, 0.01),
                knot(2000.0, 0.0, 0.0),
            ],
            Extrapolate::Error,
        )
        .unwrap()
    }

    #[test]
    fn one_interval_search_gives_each_splines_own_value() {
        // Knots unevenly spaced, every component moving: the shared search against each
        // spline's own, at the knots, between them, by the ends and past them (clamped), bit
        // for bit.
        let knots = (0..9)
            .map(|i| {
                let s = f64::from(i) * 1000.0 + f64::from(i * i) * 37.5;
                let c = [1.0, -0.5, 0.25, 0.01, -0.02, 0.03].map(|a| a * (s / 700.0).sin());
                Knot::from_components(s, c)
            })
            .collect();
        let p = Profile::from_knots("t", knots, Extrapolate::Clamp).unwrap();
        let (min, max) = p.skid_range();
        let mut skids: Vec<f64> = p.splines()[0].knots().to_vec();
        skids.extend((0..=400).map(|k| min + (max - min) * f64::from(k) / 400.0));
        skids.extend([min + 1e-9, max - 1e-9, min - 5.0, max + 5.0]);
        for s in skids {
            let own = p.splines().each_ref().map(|sp| sp.value(s.clamp(min, max)));
            assert_eq!(
                p.deviation_components(s).unwrap().map(f64::to_bits),
                own.map(f64::to_bits),
                "{s}"
            );
        }
    }

    #[test]
    fn deviation_passes_through_knots_and_refuses_outside() {
        let p = sample();
        let d = p.deviation(1000.0).unwrap();
        assert!((d.translation.z + 1.0).abs() < 1e-12);
        match p.deviation(2000.5) {
            Err(TrackError::OutOfRange { skid, min, max }) => {
                assert_eq!((skid, min, max), (2000.5, 0.0, 2000.0))
            }
            other => panic!("{other:?}"),
        }
        let c = p.clone().with_extrapolate(Extrapolate::Clamp);
        assert_eq!(
            c.deviation_components(2500.0).unwrap(),
            c.deviation_components(2000.0).unwrap()
        );
        let l = p.with_extrapolate(Extrapolate::Linear);
        let slope = l.splines()[2].derivative(2000.0);
        let v = l.deviation_components(2100.0).unwrap()[2];
        assert!((v - 100.0 * slope).abs() < 1e-12);
    }

    #[test]
    fn save_load_round_trip() {
        let p = sample();
        let text = p.to_toml_string().unwrap();
        let back = Profile::from_toml_str(&text, Path::new("p.toml")).unwrap();
        assert_eq!(back, p);
    }

    #[test]
    fn knot_uncertainties_round_trip_and_stay_optional() {
        let p = sample();
        let text = p.to_toml_string().unwrap();
        assert!(!text.contains("u_dx"), "{text}");
        let u = [KnotUncertainty {
            u: [0.01, 0.02, 0.03, 0.0004, 0.0005, 0.0006],
            centre: [1200.04, 0.0, 850.0],
            centre_xyz: [0.006; 3],
        }; 3];
        let with = p.with_knot_uncertainties(&u).unwrap();
        let text = with.to_toml_string().unwrap();
        assert!(text.contains("u_dz = 0.03"), "{text}");
        assert!(text.contains("u_centre = [1200.0, 0.0, 850.0]"), "{text}");
        let back = Profile::from_toml_str(&text, Path::new("p.toml")).unwrap();
        assert_eq!(back.knots()[1].uncertainty(), Some(u[1].u));
        assert_eq!(
            back.knots()[1].centre_uncertainty(),
            Some(([1200.0, 0.0, 850.0], [0.006; 3]))
        );
        assert!(sample().with_knot_uncertainties(&u[..2]).is_err());
    }

    #[test]
    fn uncertainties_that_are_none_are_located_errors() {
        let u = [KnotUncertainty {
            u: [0.01, 0.02, 0.03, 0.0004, 0.0005, 0.0006],
            centre: [1200.0, 0.0, 850.0],
            centre_xyz: [0.006; 3],
        }; 3];
        let text = sample()
            .with_knot_uncertainties(&u)
            .unwrap()
            .to_toml_string()
            .unwrap();
        // The second knot's line `u_ry = 0.0005` (1-based line and column where it starts).
        let second = text.match_indices("[[knot]]").nth(1).unwrap().0;
        let at = second + text[second..].find("u_ry = 0.0005").unwrap();
        let line = text[..at].matches('\n').count() + 1;
        for (bad, shown) in [
            ("u_ry = -0.0005", "u_ry = -0.0005"),
            ("u_ry = nan", "u_ry = NaN"),
            ("u_ry = inf", "u_ry = inf"),
        ] {
            let edited = format!(
                "{}{}{}",
                &text[..at],
                bad,
                &text[at + "u_ry = 0.0005".len()..]
            );
            let e = Profile::from_toml_str(&edited, Path::new("p.toml")).unwrap_err();
            let msg = e.to_string();
            assert!(msg.contains(&format!("p.toml:{line}:1")), "{msg}");
            assert!(msg.contains(&format!("[[knot]] 2: {shown}")), "{msg}");
        }
        let centre = text.replace(
            "u_centre = [1200.0, 0.0, 850.0]",
            "u_centre = [nan, 0.0, 850.0]",
        );
        let e = Profile::from_toml_str(&centre, Path::new("p.toml")).unwrap_err();
        assert!(e.to_string().contains("[[knot]] 1: u_centre = NaN"), "{e}");
        let spread = text.replace(
            "u_centre_xyz = [0.006, 0.006, 0.006]",
            "u_centre_xyz = [0.006, -1.0, 0.006]",
        );
        assert_ne!(spread, text);
        let e = Profile::from_toml_str(&spread, Path::new("p.toml")).unwrap_err();
        assert!(
            e.to_string().contains("[[knot]] 1: u_centre_xyz = -1"),
            "{e}"
        );
        // A negative centre coordinate is a position, not an uncertainty.
        let west = text.replace(
            "u_centre = [1200.0, 0.0, 850.0]",
            "u_centre = [-1200.0, 0.0, 850.0]",
        );
        assert!(Profile::from_toml_str(&west, Path::new("p.toml")).is_ok());
    }

    #[test]
    fn unknown_and_missing_keys_are_named() {
        let text = sample().to_toml_string().unwrap();
        let bad = text.replace("name = ", "colour = \"red\"\nname = ");
        let e = Profile::from_toml_str(&bad, Path::new("p.toml")).unwrap_err();
        assert!(e.to_string().contains("colour"), "{e}");
        let missing = text.replace("extrapolate = \"error\"\n", "");
        let e = Profile::from_toml_str(&missing, Path::new("p.toml")).unwrap_err();
        assert!(e.to_string().contains("extrapolate"), "{e}");
    }

    #[test]
    fn an_error_line_shows_its_utf8_comment_as_written() {
        // TOML is UTF-8: the `·` (2 bytes) is one character, and the caret under `x` stays
        // under it.
        let text = sample().to_toml_string().unwrap();
        let bad = text.replace("extrapolate = \"error\"", "extrapolate = 7 # 1.0·s");
        let e = Profile::from_toml_str(&bad, Path::new("p.toml"))
            .unwrap_err()
            .to_string();
        assert!(e.contains(" | extrapolate = 7 # 1.0·s\n"), "{e}");
        assert!(!e.contains('Â'), "{e}");
    }
}
