//! A new pose → edits of exactly the literal fields that change (docs/design.md §5 formatting).

use crate::geometry::{Pose, abb_quat_components, angle_between, kuka_abc_angles};
use crate::position::{BitField, CartesianFields, NumField, Orientation};
use crate::syntax::Edit;

/// At least this many decimals for mm.
pub(crate) const MM_DECIMALS: usize = 3;
/// At least this many decimals for quaternion components.
pub(crate) const QUAT_DECIMALS: usize = 6;
/// At least this many decimals for degrees.
pub(crate) const DEG_DECIMALS: usize = 4;

/// Below this rotation change (rad) the orientation text is kept as written, even when the
/// file's quaternion is not normalised: a zero-deviation profile must leave a file
/// byte-identical, and 1e-10 rad is far below any written precision.
const SAME_ROTATION_RAD: f64 = 1e-10;

/// How to choose among equivalent orientation numbers.
#[derive(Clone, Copy, Debug)]
pub(crate) enum OrientationHint {
    /// Keep the written numbers' branch: quaternion sign / ABC triple nearest the original.
    NearOriginal,
    /// A quaternion the result should lie close to (a mirror knows its analytic image).
    /// KUKA angles are then written in the canonical range (-180, 180].
    Expected([f64; 4]),
}

/// An edit for `field` showing `new`, if it changes at the written precision.
pub(crate) fn number_edit(field: &Option<NumField>, new: f64, min_decimals: usize) -> Option<Edit> {
    if !new.is_finite() {
        return None;
    }
    let f = field.as_ref()?;
    let text = f.lit().rewrite(new, min_decimals)?;
    Some(Edit::new(f.span(), text))
}

/// An edit for an integer field (`cf1`…), if it changes.
pub(crate) fn integer_edit(field: &Option<NumField>, new: i64) -> Option<Edit> {
    let f = field.as_ref()?;
    Some(Edit::new(f.span(), f.lit().rewrite_integer(new)?))
}

/// An edit for a KUKA Status/Turn, if it changes.
pub(crate) fn bits_edit(field: &Option<BitField>, new: u32) -> Option<Edit> {
    let f = field.as_ref()?;
    Some(Edit::new(f.span, f.rewrite(new)?))
}

fn written<const N: usize>(fields: &[Option<NumField>; N]) -> Option<[f64; N]> {
    let mut out = [0.0; N];
    for (o, f) in out.iter_mut().zip(fields) {
        *o = f.as_ref()?.value();
    }
    Some(out)
}

/// Edits that make `fields` say `new`. Fields whose text already says the new value (at their
/// written precision) are kept.
pub(crate) fn pose_edits(fields: &CartesianFields, new: &Pose, hint: OrientationHint) -> Vec<Edit> {
    let mut edits = Vec::new();
    // Absurd literals (1e300 mm) overflow the composition; a half-written target would be worse
    // than none, so such a pose changes nothing.
    let finite = new.translation.vector.iter().all(|v| v.is_finite())
        && new.rotation.coords.iter().all(|v| v.is_finite());
    if !finite {
        return edits;
    }
    let t = new.translation.vector;
    for (field, v) in fields.trans.iter().zip([t.x, t.y, t.z]) {
        edits.extend(number_edit(field, v, MM_DECIMALS));
    }
    let Some(old) = fields.pose() else {
        return edits;
    };
    if angle_between(&old.rotation, &new.rotation) < SAME_ROTATION_RAD {
        return edits;
    }
    match &fields.orient {
        Some(Orientation::Quaternion(q)) => {
            let like = match hint {
                OrientationHint::NearOriginal => written(q),
                OrientationHint::Expected(e) => Some(e),
            };
            let c = abb_quat_components(&new.rotation, like);
            for (field, v) in q.iter().zip(c) {
                edits.extend(number_edit(field, v, QUAT_DECIMALS));
            }
        }
        Some(Orientation::Abc(abc)) => {
            let like = match hint {
                OrientationHint::NearOriginal => written(abc),
                OrientationHint::Expected(_) => None,
            };
            let angles = kuka_abc_angles(&new.rotation, like);
            for (field, v) in abc.iter().zip(angles) {
                edits.extend(number_edit(field, v, DEG_DECIMALS));
            }
        }
        None => {}
    }
    edits
}

/// Translation (mm) and rotation (degrees) between two poses: the "size" of a change.
pub(crate) fn pose_change(a: &Pose, b: &Pose) -> (f64, f64) {
    let mm = (a.translation.vector - b.translation.vector).norm();
    let deg = angle_between(&a.rotation, &b.rotation).to_degrees();
    (mm, deg)
}

/// `[w, i, j, k]` of a quaternion (ABB order).
#[cfg(test)]
pub(crate) fn wijk(q: &nalgebra::UnitQuaternion<f64>) -> [f64; 4] {
    let q = q.quaternion();
    [q.w, q.i, q.j, q.k]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{abb_quat, pose_xyz_deg};
    use crate::syntax::{NumLit, Span};

    fn field(text: &str, at: usize) -> Option<NumField> {
        NumField::new(
            Span::new(at, at + text.len()),
            NumLit::parse(text.as_bytes()).unwrap(),
        )
    }

    fn quat_fields(t: [&str; 3], q: [&str; 4]) -> CartesianFields {
        CartesianFields {
            trans: [field(t[0], 0), field(t[1], 10), field(t[2], 20)],
            orient: Some(Orientation::Quaternion([
                field(q[0], 30),
                field(q[1], 40),
                field(q[2], 50),
                field(q[3], 60),
            ])),
        }
    }

    #[test]
    fn unchanged_pose_gives_no_edits_even_for_an_unnormalised_quaternion() {
        let f = quat_fields(["100", "0", "9.5"], ["0.7071", "0", "0.7071", "0"]);
        let p = f.pose().unwrap();
        assert!(pose_edits(&f, &p, OrientationHint::NearOriginal).is_empty());
    }

    #[test]
    fn writes_only_changed_fields_with_house_decimals() {
        let f = quat_fields(["100", "0", "9.5"], ["1", "0", "0", "0"]);
        let p = f.pose().unwrap();
        let moved = Pose::from_parts(
            nalgebra::Translation3::new(100.25, 0.0, 9.5),
            abb_quat([1.0, 0.0, 0.0, 0.0]).unwrap(),
        );
        let e = pose_edits(&f, &moved, OrientationHint::NearOriginal);
        assert_eq!(e, vec![Edit::new(Span::new(0, 3), "100.250")]);
        let turned = p * pose_xyz_deg(0.0, 0.0, 0.0, 0.0, 0.0, 90.0);
        let e = pose_edits(&f, &turned, OrientationHint::NearOriginal);
        let texts: Vec<String> = e
            .iter()
            .map(|e| String::from_utf8(e.text.to_vec()).unwrap())
            .collect();
        assert_eq!(texts, ["0.707107", "0.707107"]);
    }

    #[test]
    fn non_finite_results_write_nothing() {
        let f = quat_fields(["1e300", "0", "0"], ["1", "0", "0", "0"]);
        let p = f.pose().unwrap();
        let huge = Pose::from_parts(
            nalgebra::Translation3::new(f64::INFINITY, 0.0, 0.0),
            p.rotation,
        );
        assert!(pose_edits(&f, &huge, OrientationHint::NearOriginal).is_empty());
        assert_eq!(number_edit(&f.trans[1], f64::NAN, 3), None);
    }

    #[test]
    fn quaternion_sign_follows_the_original() {
        let f = quat_fields(["0", "0", "0"], ["-1", "0", "0", "0"]);
        let turned = f.pose().unwrap() * pose_xyz_deg(0.0, 0.0, 0.0, 0.0, 0.0, 1.0);
        let e = pose_edits(&f, &turned, OrientationHint::NearOriginal);
        assert_eq!(String::from_utf8(e[0].text.to_vec()).unwrap(), "-0.999962");
    }
}
