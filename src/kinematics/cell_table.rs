//! `[robot.NAME.kinematics]` of the cell file: the OPW lengths, joint map and limits, or a
//! bundled `model` with optional overrides.
//!
//! ```toml
//! [robot.r1.kinematics]
//! model = "abb_irb2400_10"          # or every length below
//! a1 = 100.0                        # mm: a1 a2 b c1 c2 c3 c4
//! offsets = [0, 0, -90, 0, 0, 0]    # degrees, q = sign·θ − offset
//! signs = [1, 1, 1, 1, 1, 1]
//! limits = [[-180, 180], [-100, 110], [-60, 65], [-200, 200], [-120, 120], [-400, 400]]
//! ```

use serde::Deserialize;
use toml::Spanned;

use super::models::{model, model_names};
use super::opw::{Kinematics, OpwGeometry};
use crate::syntax::Span;

/// The table as written (the cell file deserialises it; [`KinematicsToml::resolve`] validates).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KinematicsToml {
    model: Option<Spanned<String>>,
    a1: Option<Spanned<f64>>,
    a2: Option<Spanned<f64>>,
    b: Option<Spanned<f64>>,
    c1: Option<Spanned<f64>>,
    c2: Option<Spanned<f64>>,
    c3: Option<Spanned<f64>>,
    c4: Option<Spanned<f64>>,
    offsets: Option<Spanned<[f64; 6]>>,
    signs: Option<Spanned<[f64; 6]>>,
    limits: Option<Spanned<[[f64; 2]; 6]>>,
}

/// A problem in the table, at `span` of the cell file.
#[derive(Clone, Debug, PartialEq)]
pub struct TableError {
    /// The bytes of the cell file the problem is at.
    pub span: Span,
    /// What is wrong.
    pub message: String,
    /// What to do.
    pub hint: String,
}

fn err(span: impl Into<Span>, message: String, hint: &str) -> TableError {
    TableError {
        span: span.into(),
        message,
        hint: hint.to_owned(),
    }
}

impl KinematicsToml {
    /// The robot's kinematics; `table` is the span of the whole table (for a missing key).
    pub fn resolve(&self, robot: &str, table: Span) -> Result<Kinematics, TableError> {
        let base = match &self.model {
            Some(m) => Some(
                model(m.get_ref())
                    .ok_or_else(|| {
                        err(
                            m.span(),
                            format!("robot `{robot}`: unknown robot model `{}`", m.get_ref()),
                            &format!(
                                "bundled models: {}; or give a1 a2 b c1 c2 c3 c4 and limits",
                                model_names().join(", ")
                            ),
                        )
                    })?
                    .kinematics(),
            ),
            None => None,
        };
        let length = |v: &Option<Spanned<f64>>, name: &str, from: Option<f64>| match (v, from) {
            (Some(s), _) if s.get_ref().is_finite() => Ok(*s.get_ref()),
            (Some(s), _) => Err(err(
                s.span(),
                format!("robot `{robot}`: kinematics `{name}` is not a finite number"),
                "write the length in mm",
            )),
            (None, Some(f)) => Ok(f),
            (None, None) => Err(err(
                table,
                format!("robot `{robot}`: kinematics has no `{name}`"),
                "give all of a1 a2 b c1 c2 c3 c4 (mm), or `model = \"NAME\"`",
            )),
        };
        let g = base.as_ref().map(|k| k.geometry);
        let geometry = OpwGeometry {
            a1: length(&self.a1, "a1", g.map(|g| g.a1))?,
            a2: length(&self.a2, "a2", g.map(|g| g.a2))?,
            b: length(&self.b, "b", g.map(|g| g.b))?,
            c1: length(&self.c1, "c1", g.map(|g| g.c1))?,
            c2: length(&self.c2, "c2", g.map(|g| g.c2))?,
            c3: length(&self.c3, "c3", g.map(|g| g.c3))?,
            c4: length(&self.c4, "c4", g.map(|g| g.c4))?,
        };
        if geometry.c2 <= 0.0 || geometry.a2.hypot(geometry.c3) <= 0.0 {
            let span = self
                .c2
                .as_ref()
                .map(|s| Span::from(s.span()))
                .unwrap_or(table);
            return Err(err(
                span,
                format!("robot `{robot}`: kinematics needs c2 > 0 and a forearm (a2, c3) ≠ 0"),
                "c2 is the upper arm (axis 2 to axis 3), c3 the forearm (axis 3 to the wrist)",
            ));
        }
        let offsets = match (&self.offsets, &base) {
            (Some(o), _) => {
                if o.get_ref().iter().any(|v| !v.is_finite()) {
                    return Err(err(
                        o.span(),
                        format!("robot `{robot}`: kinematics offsets must be numbers"),
                        "six angles in degrees",
                    ));
                }
                *o.get_ref()
            }
            (None, Some(k)) => k.offsets,
            (None, None) => [0.0; 6],
        };
        let signs = match (&self.signs, &base) {
            (Some(s), _) => {
                if s.get_ref().iter().any(|v| *v != 1.0 && *v != -1.0) {
                    return Err(err(
                        s.span(),
                        format!("robot `{robot}`: kinematics signs must be 1 or -1"),
                        "one sign per axis: -1 where the controller turns against the model",
                    ));
                }
                *s.get_ref()
            }
            (None, Some(k)) => k.signs,
            (None, None) => [1.0; 6],
        };
        let limits = match (&self.limits, &base) {
            (Some(l), _) => {
                let bad = l
                    .get_ref()
                    .iter()
                    .position(|[lo, hi]| !(lo.is_finite() && hi.is_finite() && lo < hi));
                if let Some(i) = bad {
                    return Err(err(
                        l.span(),
                        format!(
                            "robot `{robot}`: kinematics limit of axis {} is not [min, max] with min < max",
                            i + 1
                        ),
                        "six pairs [min, max] in degrees",
                    ));
                }
                *l.get_ref()
            }
            (None, Some(k)) => k.limits,
            (None, None) => {
                return Err(err(
                    table,
                    format!("robot `{robot}`: kinematics has no `limits`"),
                    "give six [min, max] joint limits in degrees (the robot's product specification)",
                ));
            }
        };
        Ok(Kinematics {
            geometry,
            offsets,
            signs,
            limits,
        })
    }
}
