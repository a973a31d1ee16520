//! The refusal and frame-resolution rules every transform shares (docs/design.md §4): which targets
//! no transform touches, and how a target's work object (or KRL base) becomes a pose in world.

use std::collections::BTreeMap;

use crate::dialect::Vocabulary;
use crate::geometry::Pose;
use crate::position::{
    FrameKind, FrameName, ParsedFile, Position, Program, TwoValues, UnresolvedCause,
};

use super::refusal::{Refusal, RefusalKind, Remedy};

/// Coordinates beyond this (mm) are not a target in a robot cell.
const PLAUSIBLE_MM: f64 = 1e6;

/// Why a target is refused, before it is located in a file.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Why {
    pub kind: RefusalKind,
    pub message: String,
    /// What to do, in words.
    pub hint: String,
    /// The transform setting that gets past it, if any.
    pub remedy: Option<Remedy>,
}

impl Why {
    pub(crate) fn new(kind: RefusalKind, message: String, hint: impl Into<String>) -> Why {
        Why {
            kind,
            message,
            hint: hint.into(),
            remedy: None,
        }
    }

    pub(crate) fn with_remedy(mut self, remedy: Remedy) -> Why {
        self.remedy = Some(remedy);
        self
    }

    /// The refusal of offset call `call` in `file` for this reason.
    pub(crate) fn at_call(
        self,
        file: &ParsedFile,
        call: &crate::position::OffsetCall,
    ) -> Box<Refusal> {
        Box::new(Refusal::new(
            file,
            call.span,
            call.target.clone(),
            self.kind,
            self.message,
            self.hint,
            self.remedy,
        ))
    }

    /// The refusal of `p` in `file` for this reason.
    pub(crate) fn at(self, file: &ParsedFile, p: &Position) -> Box<Refusal> {
        Box::new(Refusal::new(
            file,
            p.span,
            p.label(),
            self.kind,
            self.message,
            self.hint,
            self.remedy,
        ))
    }
}

/// Names that mean "world" when a program does not declare them, in any dialect.
fn is_world(name: &str) -> bool {
    let n = name.to_ascii_lowercase();
    crate::dialect::any(|d| d.vocabulary().world_frames.contains(&n.as_str()))
}

/// The work object / base `name` in world: the cell's override, else the program's
/// declaration (that of `own`, the file of the target, first: two RAPID modules may each declare
/// a `LOCAL` work object of one name), else world for `wobj0`.
pub(crate) fn resolve_frame(
    program: &Program,
    own: Option<&ParsedFile>,
    overrides: &BTreeMap<String, Pose>,
    name: &str,
) -> Result<Pose, Why> {
    let decl = program
        .frame_seen_from(own, name, |k| {
            matches!(k, FrameKind::WorkObject | FrameKind::Base)
        })
        .map(|(f, d)| (d, f.language));
    // The words of the language that declares the frame, else of the program's.
    let words = decl.map_or_else(|| words_of(program), |(_, l)| l.dialect().vocabulary());
    let frame = words.frame;
    let overridden = overrides.get(&super::cell::frame_key(name)).copied();
    match (decl.map(|(d, _)| d), overridden) {
        (Some(d), _) if d.fixed == Some(false) => Err(Why::new(
            RefusalKind::MovingWorkObject,
            format!(
                "{frame} `{name}` is moved by a mechanical unit ({})",
                words.moved_frame
            ),
            "its position depends on that unit, not on the track: correct such targets by hand",
        )),
        (Some(d), _) if d.held_by_robot == Some(true) => Err(Why::new(
            RefusalKind::StationaryTool,
            format!(
                "{frame} `{name}` is held by the robot ({}: stationary tool)",
                words.stationary_tool
            ),
            "a stationary-tool target moves with the work piece, not the track: correct it by hand",
        )),
        // The program gives the frame another value before it moves, which the robot then
        // moves in: the cell's frame stands for the declaration, not for that value.
        (Some(d), Some(_)) if d.assigned => Err(Why::new(
            RefusalKind::RuntimeData,
            format!(
                "{frame} `{name}` is given another value by the program (line {}) than the declaration the cell file's entry for it replaces: the robot moves in the program's value",
                d.line
            ),
            format!(
                "remove `{name}` from the cell file's [robot.NAME.wobj], or declare it with the value the program gives it"
            ),
        )),
        // The cell's identified frame stands for the declared one, which still says whether
        // the frame moves with another unit or is held by the robot. It is the user frame: a
        // RAPID work object's object frame (`oframe`, the part placed in its fixture) is the
        // program's, which a measurement of the user frame does not change
        // (`cell::frame_readings` says so at the declaration).
        (d, Some(p)) => match d.and_then(|d| d.oframe.as_ref()) {
            None => Ok(p),
            Some(o) => o.pose().map(|o| p * o).ok_or_else(|| {
                Why::new(
                    RefusalKind::UnresolvedWorkObject,
                    format!(
                        "{frame} `{name}` has an object frame (oframe) with fields that are not numbers: the cell file's entry gives its user frame only"
                    ),
                    format!("write the oframe of `{name}` as numbers"),
                )
            }),
        },
        (Some(d), None) => d.pose().ok_or_else(|| {
            Why::new(
                RefusalKind::UnresolvedWorkObject,
                format!("{frame} `{name}` has fields that are not numbers"),
                format!(
                    "give `{name}` as {{x,y,z,rx,ry,rz}} under [robot.NAME.wobj] in the cell file"
                ),
            )
        }),
        (None, None) if is_world(name) => Ok(Pose::identity()),
        // Declared, but where the target's file does not see it (`LOCAL` in another module).
        (None, None) => Err(match hidden_declaration(program, name) {
            Some(file) => Why::new(
                RefusalKind::UnresolvedWorkObject,
                format!(
                    "{frame} `{name}` is declared LOCAL in {}, which the target's module does not see",
                    file.path.display()
                ),
                format!(
                    "declare `{name}` where the target's module sees it (without LOCAL), or give it under [robot.NAME.wobj] in the cell file"
                ),
            ),
            None => Why::new(
                RefusalKind::UnresolvedWorkObject,
                format!("{frame} `{name}` is not declared in the program"),
                format!(
                    "if `{name}` is one fixed frame, give it under [robot.NAME.wobj] in the cell file; a routine's parameter or a {frame} chosen at run time is not: write each motion with the {frame} it runs in"
                ),
            ),
        }),
    }
}

/// The file that declares work object `name` `LOCAL` to itself, if one does.
fn hidden_declaration<'p>(program: &'p Program, name: &str) -> Option<&'p ParsedFile> {
    program.files.iter().find(|f| {
        f.frames.iter().any(|d| {
            d.scope == crate::position::FrameScope::Module
                && matches!(d.kind, FrameKind::WorkObject | FrameKind::Base)
                && d.name.eq_ignore_ascii_case(name)
        })
    })
}

/// The work object (or KRL base) a target is used with: its first use, else `default` for a
/// declared target no motion uses. `words` are the target's language's.
pub(crate) fn wobj_of(
    p: &Position,
    default: Option<&str>,
    words: &Vocabulary,
) -> Result<String, Why> {
    let what = describe(p);
    let frame = words.frame;
    if let Some(u) = p.usage.unresolved_frame() {
        let at = &u.at;
        return Err(match &u.cause {
            UnresolvedCause::SomePaths => Why::new(
                RefusalKind::UnresolvedWorkObject,
                format!("{what} is moved to on {at} with a {frame} that cannot be resolved"),
                words.frame_of_a_motion,
            ),
            UnresolvedCause::Parameter(name) => Why::new(
                RefusalKind::UnresolvedWorkObject,
                format!(
                    "{what} is moved to on {at} with `{name}`, a parameter of the routine: the {frame} is whichever one each caller passes"
                ),
                format!("name the {frame} in the motion itself"),
            ),
            UnresolvedCause::PassedTo(routine) => Why::new(
                RefusalKind::UnresolvedWorkObject,
                format!(
                    "{what} is passed to `{routine}` on {at}, whose motions trackfix does not follow: the {frame} they move in is not known"
                ),
                format!(
                    "move to it where it is declared, with the {frame} set there, or correct it by hand"
                ),
            ),
            UnresolvedCause::ChangedBy(routine) => Why::new(
                RefusalKind::UnresolvedWorkObject,
                format!(
                    "{what} is moved to on {at}, and `{routine}` changes the {frame}, the tool or the interpolation mode when it runs (a function, or the routine of an interrupt or trigger), which trackfix does not follow"
                ),
                format!(
                    "set the {frame} in the routines that move, not in `{routine}`, or correct the targets by hand"
                ),
            ),
            UnresolvedCause::HandedBack(how) => Why::new(
                RefusalKind::UnresolvedWorkObject,
                format!(
                    "{what} is {how} on {at}: trackfix does not follow the value to the motions that move to it, so the {frame} they move in is not known"
                ),
                format!(
                    "move to it where it is declared, with the {frame} set there, or correct it by hand"
                ),
            ),
            UnresolvedCause::Member(whole) => structure_member(p, whole),
            UnresolvedCause::Shadowed(name) => Why::new(
                RefusalKind::UnresolvedWorkObject,
                format!(
                    "{what} is moved to on {at} with `{name}`, which means another declaration there than where the target is declared (a LOCAL one, or a routine's own)"
                ),
                format!(
                    "give the {frame}s of one name one declaration the motions and targets both see"
                ),
            ),
        });
    }
    match (&p.usage.wobj, p.usage.lines.is_empty()) {
        (Some(w), _) => Ok(w.to_string()),
        (None, true) => match default {
            Some(d) => Ok(d.to_owned()),
            None => Err(Why::new(
                RefusalKind::UnresolvedWorkObject,
                format!("{what} is not used by any motion: its {frame} is unknown"),
                format!("name the {frame} of targets no motion uses"),
            )
            .with_remedy(Remedy::DefaultWorkObject)),
        },
        (None, false) => Err(Why::new(
            RefusalKind::UnresolvedWorkObject,
            format!("{what} is used with a {frame} that cannot be resolved"),
            words.frame_of_a_motion,
        )),
    }
}

/// The refusal of a KRL point held in a member of the structure `whole` (as written): checked
/// before any other, since whatever the motions trackfix sees say, the structure may carry the
/// point to one it does not.
fn structure_member(p: &Position, whole: &str) -> Why {
    Why::new(
        RefusalKind::StructureMember,
        format!(
            "{} is held in a member of the structure `{whole}`: trackfix does not follow a structure's members everywhere the program may take them (a copy of the whole structure, an array of structures, a parameter, another module), so which base the robot moves to it in is not known",
            describe(p)
        ),
        "declare the point as an E6POS of its own and move to it (copy it into the member where the structure needs it), or correct it by hand",
    )
}

/// The words of `program`'s language (an empty program has none: RAPID's, as the cell file's
/// `wobj` key).
pub(crate) fn words_of(program: &Program) -> &'static Vocabulary {
    program
        .language()
        .unwrap_or(crate::position::Language::Rapid)
        .dialect()
        .vocabulary()
}

/// The pose in world of the work object `p` (a target of file `own`) is used with (`frames`
/// override the program's).
pub(crate) fn work_object_of(
    program: &Program,
    own: Option<&ParsedFile>,
    p: &Position,
    frames: &BTreeMap<String, Pose>,
    default: Option<&str>,
) -> Result<Pose, Why> {
    let name = wobj_of(p, default, words_of(program))?;
    resolve_frame(program, own, frames, &name).map_err(|why| Why {
        message: format!("{}: {}", describe(p), why.message),
        ..why
    })
}

/// The work object [`work_object_of`] last resolved by name, for the targets after it: a
/// program's targets are used with a handful of work objects, in long runs of one, and
/// resolving one by name (its text copied and lower-cased, the overrides searched) was 2 % of
/// `correct`. What a name resolves to depends on the program and the overrides only, which a
/// rule keeps for its whole run; a name that does not resolve is resolved again each time (the
/// refusal names the target).
#[derive(Default)]
pub(crate) struct LastWorkObject(std::cell::RefCell<Option<(FrameName, usize, Pose)>>);

impl LastWorkObject {
    /// [`work_object_of`], for the same `program`, `frames` and `default` at every call. A name
    /// is resolved again in another file (its own declaration comes first).
    pub(crate) fn work_object_of(
        &self,
        program: &Program,
        own: &ParsedFile,
        p: &Position,
        frames: &BTreeMap<String, Pose>,
        default: Option<&str>,
    ) -> Result<Pose, Why> {
        let Some(name) = &p.usage.wobj else {
            return work_object_of(program, Some(own), p, frames, default);
        };
        // The file by its address: the program holds it for the whole run.
        let file = std::ptr::from_ref(own) as usize;
        if let Some((last, in_file, pose)) = &*self.0.borrow()
            && last == name
            && *in_file == file
        {
            return Ok(*pose);
        }
        let pose = work_object_of(program, Some(own), p, frames, default)?;
        *self.0.borrow_mut() = Some((name.clone(), file, pose));
        Ok(pose)
    }
}

/// `robtarget \`p10\`` for a declared target, `inline robtarget` for a literal in an instruction.
///
/// Written only when a message is: every target of a transform is described by several checks,
/// and most of them pass (formatting eagerly was 7 % of `correct`).
pub(crate) fn describe(p: &Position) -> Described<'_> {
    Described(p)
}

/// A target's name for messages, formatted on display ([`describe`]).
#[derive(Clone, Copy)]
pub(crate) struct Described<'a>(&'a Position);

impl std::fmt::Display for Described<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match &self.0.name {
            Some(n) => write!(f, "{} `{n}`", self.0.kind.as_str()),
            None => write!(f, "inline {}", self.0.kind.as_str()),
        }
    }
}

/// The refusal of a target whose value the program computes when it runs (`p10 := CRobT()`,
/// `jPark := CalcJointT(…)`), or that is used with a frame computed then: what a transform
/// writes into its literal would not be what the robot moves to.
pub(crate) fn run_time(p: &Position) -> Option<Why> {
    let why = p.usage.run_time()?;
    Some(Why::new(
        RefusalKind::RuntimeData,
        format!(
            "{} {}: not correctable offline",
            describe(p),
            why.describe()
        ),
        why.hint(),
    ))
}

/// The targets of a program left as written whose `Offs`/`RelTool` calls stay as written with
/// them: a point as written with a mirrored offset is neither. Not a target computed at run
/// time, whose offset applies to the pose the robot computes and moves as the offsets of a
/// target without a literal do. By (file, index): a call's bases are resolved where it is
/// written ([`OffsetCall::bases`]), in any module.
///
/// [`OffsetCall::bases`]: crate::position::OffsetCall::bases
pub(crate) struct KeptTargets(std::collections::HashSet<(usize, usize)>);

impl KeptTargets {
    /// The targets refused, as ((file, index), kind).
    pub(crate) fn of(refused: impl IntoIterator<Item = ((usize, usize), RefusalKind)>) -> Self {
        KeptTargets(
            refused
                .into_iter()
                .filter(|(_, kind)| !kind.is_runtime_data())
                .map(|(at, _)| at)
                .collect(),
        )
    }

    /// Whether `call` offsets one of the targets.
    pub(crate) fn offsets(&self, call: &crate::position::OffsetCall) -> bool {
        self.kept_bases(call) > 0
    }

    /// How many of the targets `call` stands for are kept.
    pub(crate) fn kept_bases(&self, call: &crate::position::OffsetCall) -> usize {
        if self.0.is_empty() {
            return 0;
        }
        call.bases.iter().filter(|b| self.0.contains(b)).count()
    }
}

/// Why an offset call that stands for targets some of which are left as written (`kept` of
/// them) and some moved is refused: kept, it is right for the first; moved, for the others.
pub(crate) fn partly_kept_offset(call: &crate::position::OffsetCall, kept: usize) -> Why {
    Why::new(
        RefusalKind::SharedOffset,
        format!(
            "`{}` stands for {} targets, {kept} of them left as written and the others moved: one offset cannot follow both",
            call.target,
            call.bases.len()
        ),
        "write the offset point of each as a target of its own, or fix the targets left as written",
    )
}

/// What every transform says of a target the program uses as other than a position
/// ([`NonPosition`](crate::position::NonPosition)): a note where it stays right as written under
/// the rule (`keeps`: a tolerance always; joint limits and offsets under the track rules,
/// which keep the joint ranges and move a composed frame with the frame before its `:`), else
/// a refusal (a mirror's joint limits and offsets, which no transform of one target gives).
pub(crate) fn non_position(np: &crate::position::NonPosition, p: &Position, keeps: bool) -> Why {
    use crate::position::NonPositionRole::{Found, Limit, Offset, Tolerance};
    let crate::position::NonPosition {
        instruction,
        parameter,
        at,
        role,
    } = np;
    let what = describe(p);
    // Moved to as well: one value cannot be both corrected as a position and kept as an
    // offset (nor mirrored as both).
    if *role == Offset
        && let Some(&line) = p.usage.lines.first()
    {
        return Why::new(
            RefusalKind::ComposedOffset,
            format!(
                "{what} is moved to by a motion (line {line}) and is also the {parameter} of `{instruction}` on {at}: one value cannot be both a position and an offset"
            ),
            "declare a point of its own for each of the two uses",
        );
    }
    let relative = *parameter == "relative target";
    let used = match role {
        Offset => format!("{what} is the {parameter} of `{instruction}` on {at}"),
        Tolerance | Limit | Found => {
            format!("{what} is the `{parameter}` of `{instruction}` on {at}")
        }
    };
    let is = match role {
        Tolerance => "a tolerance",
        Limit => "joint limits",
        Offset if relative => "a displacement from wherever the robot is",
        Offset => "an offset in the frame before it",
        Found => "written by the search with the position it finds",
    };
    if keeps {
        let hint = match role {
            Tolerance => "nothing to do: a tolerance holds for every robot and track",
            Limit => "nothing to do: the robot's joint ranges are what they were",
            Offset if relative => {
                "check the motion by hand: a displacement in the base frame turns with the base's correction, one in the tool frame (#TOOL) does not"
            }
            Offset => "nothing to do: the composed frame moves with the frame before the `:`",
            Found => "nothing to do: a motion to it after the search goes where the search found",
        };
        return Why::new(
            RefusalKind::NotAPosition,
            format!("{used}: {is}, not a position; left as written"),
            hint,
        );
    }
    let (kind, hint) = match role {
        Offset => (
            RefusalKind::ComposedOffset,
            "mirror the offset by hand, in its own frame, or teach the composed point",
        ),
        Tolerance | Limit | Found => (
            RefusalKind::WorldZoneLimits,
            "set the world zone's limits for this robot by hand (mirrored: axis 1's low and high negated and swapped)",
        ),
    };
    Why::new(kind, format!("{used}: {is}, not a position"), hint)
}

/// The refusal of every transform for a joint target it does not change.
pub(crate) fn joint_target(p: &Position) -> Why {
    Why::new(
        RefusalKind::JointTarget,
        format!("{} is a joint target: it is not changed", describe(p)),
        "re-teach it or convert it to a Cartesian target",
    )
}

/// The refusal of a target moved to with a tool the robot does not hold (RAPID `tooldata`
/// `robhold FALSE`): a stationary tool, as much as a work object the robot holds
/// ([`common_refusal`]) makes one. RAPID pairs the two flags, but either says the TCP stands
/// still while the robot carries the work piece: a program that sets only one is refused all the
/// same, with or without the robot's kinematics (which otherwise find the tool unresolved).
pub(crate) fn stationary_tool(program: &Program, own: &ParsedFile, p: &Position) -> Option<Why> {
    let name = p.usage.tools().find(|name| {
        program
            .frame_seen_from(Some(own), name, |k| k == FrameKind::Tool)
            .is_some_and(|(_, d)| d.held_by_robot == Some(false))
    })?;
    Some(Why::new(
        RefusalKind::StationaryTool,
        format!(
            "{} is moved to with tool `{name}`, which the robot does not hold (robhold FALSE: stationary tool)",
            describe(p)
        ),
        "a stationary-tool target moves with the work piece, not the track: correct it by hand",
    ))
}

/// The refusal of target `p`, moved to in two values `t` of its `frame` (the language's word
/// for a work object, or "tool"), with what that does to the transform (`why`, from ": …", or
/// nothing).
fn two_values(p: &Position, frame: &str, t: &TwoValues, why: &str) -> Why {
    Why::new(
        RefusalKind::TwoWorkObjects,
        format!(
            "{} is moved to in two values of {frame} `{}`: as declared ({}) and as the program gives it ({}), since the motion on {} may run before the assignment{why}",
            describe(p),
            t.frame,
            t.declared,
            t.given,
            t.motion
        ),
        format!(
            "give `{}` its value before every motion to the target (or declare it with that value), or move to one target per value",
            t.frame
        ),
    )
}

/// The refusal of target `p` where a transform reads or writes its tool (the robot's
/// kinematics check its joints, a mirror of the frames writes the tool), `why` that matters,
/// when a motion to it may run with the tool's declared value, the program giving it another.
/// A track correction alone does not read the tool (`B·D⁻¹·B⁻¹` acts on the TCP, the same in
/// both values), nor does a mirror that leaves the frames as written.
pub(crate) fn tool_in_two_values(p: &Position, why: &str) -> Option<Why> {
    let t = p.usage.two_values(FrameKind::Tool)?;
    Some(two_values(p, "tool", t, &format!(": {why}")))
}

/// Checks that every transform makes before touching a Cartesian target; `None` = go ahead.
pub(crate) fn common_refusal(file: &ParsedFile, p: &Position) -> Option<Why> {
    let what = describe(p);
    let words = file.language.dialect().vocabulary();
    let refuse = |kind, msg: String, hint: &str| Some(Why::new(kind, msg, hint));
    if !p.kind.is_cartesian() {
        return Some(joint_target(p));
    }
    if let Some(u) = p.usage.unresolved_frame()
        && let UnresolvedCause::Member(whole) = &u.cause
    {
        return Some(structure_member(p, whole));
    }
    let written_q = p.cartesian.as_ref().and_then(|c| c.written_quaternion());
    if written_q.is_some_and(|q| q.iter().all(|v| *v == 0.0)) {
        return refuse(
            RefusalKind::ZeroQuaternion,
            format!("{what} has the quaternion [0,0,0,0]: an unset slot, not an orientation"),
            "teach the target (or leave the slot unused)",
        );
    }
    if let Some(why) = run_time(p) {
        return Some(why);
    }
    if p.cartesian.as_ref().and_then(|c| c.pose()).is_none() {
        let literal = p.span.slice(&file.source);
        // An inline target's fields left out are the robot's when the motion runs; a declared
        // one's, whatever the variable held before (nothing a file says).
        match file.language.dialect().pose_fields_left_out(literal) {
            Some(left_out) if p.name.is_none() => {
                return refuse(
                    RefusalKind::RuntimeData,
                    format!(
                        "{what} leaves out {left_out}: the controller takes them from where the robot is when the motion runs, so the target is only known then"
                    ),
                    "write every field of the target, or check this motion by hand",
                );
            }
            Some(left_out) => {
                return refuse(
                    RefusalKind::Expression,
                    format!("{what} leaves out {left_out}: its pose is not known whole"),
                    "write every field of the target",
                );
            }
            None => {}
        }
        return refuse(
            RefusalKind::Expression,
            format!("{what} has a position or orientation field that is not a number"),
            "write the fields as numeric literals",
        );
    }
    let far = p
        .cartesian
        .as_ref()
        .and_then(|c| c.translation())
        .is_some_and(|t| t.iter().any(|v| v.abs() > PLAUSIBLE_MM));
    if far {
        return refuse(
            RefusalKind::Implausible,
            format!(
                "{what} lies more than 1 km from its {}'s origin",
                words.frame
            ),
            "check the coordinates (mm)",
        );
    }
    if let Some(problem) = implausible_literal(file, p) {
        return refuse(
            RefusalKind::Implausible,
            format!("{what} {problem}"),
            "check the value: it is no configuration or orientation a controller accepts",
        );
    }
    if p.usage.stationary_tool() {
        return refuse(
            RefusalKind::StationaryTool,
            format!(
                "{what} is a stationary-tool point ({})",
                words.stationary_point
            ),
            "it moves with the work piece, not the track: correct it by hand",
        );
    }
    // Like two work objects: no one correction serves both values, where a mirror in the
    // work object's own plane is the same in each.
    if let Some(t) = p.usage.two_values(FrameKind::WorkObject) {
        return Some(two_values(p, words.frame, t, ""));
    }
    if !p.usage.other_wobjs().is_empty() {
        let first = p.usage.wobj.as_deref().unwrap_or("?");
        let others = p.usage.other_wobjs();
        let mut named: Vec<String> = std::iter::once(first)
            .chain(others.iter().map(|w| &**w))
            .map(|w| format!("`{w}`"))
            .collect();
        let count = frame_count(named.len());
        let last = named.pop().unwrap_or_default();
        return refuse(
            RefusalKind::TwoWorkObjects,
            format!(
                "{what} is used with {count} {} ({} and {last})",
                words.frames,
                named.join(", ")
            ),
            &format!("split it into one target per {}", words.frame),
        );
    }
    None
}

/// How many work objects or bases a target is used with, as the messages say it: `two`, else
/// the number.
pub(crate) fn frame_count(n: usize) -> String {
    match n {
        2 => "two".to_owned(),
        n => n.to_string(),
    }
}

/// Written angles (degrees) beyond this are no orientation: a typo or `9E9` in the wrong field.
pub(crate) const PLAUSIBLE_DEG: f64 = 360.0;
/// ABB `cf1, cf4, cf6, cfx` are quadrant and configuration numbers: small integers.
pub(crate) const PLAUSIBLE_CF: f64 = 1000.0;
/// KUKA Status: bits 0 to 2 are the arm configuration, bit 3 is unused and bit 4 marks a point
/// taught on an absolutely accurate robot (KSS 8 writes `S 18`, `S 22` for those), so 5 bits.
/// Turn has 6, one per axis.
const KUKA_STATUS_MAX: u32 = 0b1_1111;
const KUKA_TURN_MAX: u32 = 0b11_1111;
/// A written quaternion farther than this from unit length is no rotation (controllers reject
/// anything beyond a few 1e-5; the check lint warns at 1e-4).
pub(crate) const PLAUSIBLE_QUATERNION_NORM_ERROR: f64 = 0.01;

/// What makes the literals of a Cartesian target absurd, in words ("has cf4 = 1.5, …"), or
/// `None`. Shared by `check` (a finding) and every transform (a refusal).
pub(crate) fn implausible_literal(file: &ParsedFile, p: &Position) -> Option<String> {
    let orient = p.cartesian.as_ref().and_then(|c| c.orient.as_ref());
    implausible_fields(file, p.span, orient, &p.config)
}

/// The length of a written quaternion, as the lints and the plausibility checks measure it.
#[inline]
pub(crate) fn quaternion_norm(q: [f64; 4]) -> f64 {
    q.iter().map(|v| v * v).sum::<f64>().sqrt()
}

/// Whether a written quaternion of this (non-zero) length is a rotation.
#[inline]
pub(crate) fn plausible_quaternion_norm(norm: f64) -> bool {
    norm.is_finite() && (norm - 1.0).abs() <= PLAUSIBLE_QUATERNION_NORM_ERROR
}

/// Whether `v` may be one of ABB's `cf1, cf4, cf6, cfx`: a finite small integer. Compared with
/// its truncation to an integer rather than through `f64::fract`, which is a call into libm
/// on the baseline x86-64 target; the two agree within the bound.
#[inline]
pub(crate) fn plausible_cf(v: f64) -> bool {
    v.abs() <= PLAUSIBLE_CF && v == f64::from(v as i32)
}

/// [`implausible_literal`] of the target written at `span`, from the fields it looks at: its
/// orientation and configuration (`check` reads only these of each target).
pub(crate) fn implausible_fields(
    file: &ParsedFile,
    span: crate::syntax::Span,
    orient: Option<&crate::position::Orientation>,
    config: &crate::position::Config,
) -> Option<String> {
    implausible_text(file, span).or_else(|| implausible_values(orient, config))
}

/// What the dialect finds absurd in the text of the target written at `span` (a KRL Status
/// spelled out of range, say), or `None`: the part of [`implausible_fields`] that reads no
/// field.
pub(crate) fn implausible_text(file: &ParsedFile, span: crate::syntax::Span) -> Option<String> {
    file.language
        .dialect()
        .implausible_configuration(span.slice(&file.source))
}

/// The part of [`implausible_fields`] that looks at the values of the orientation and the
/// configuration only.
pub(crate) fn implausible_values(
    orient: Option<&crate::position::Orientation>,
    config: &crate::position::Config,
) -> Option<String> {
    use crate::position::{Config, Orientation};
    match orient {
        Some(Orientation::Abc(abc)) => {
            for (name, f) in ["A", "B", "C"].iter().zip(abc) {
                if let Some(f) = f
                    && !(f.value().is_finite() && f.value().abs() <= PLAUSIBLE_DEG)
                {
                    return Some(format!(
                        "has {name} = {}: not an angle in degrees",
                        shown(f.value())
                    ));
                }
            }
        }
        Some(o @ Orientation::Quaternion(_)) => {
            if let Some(q) = o.written_quaternion() {
                let norm = quaternion_norm(q);
                if norm != 0.0 && !plausible_quaternion_norm(norm) {
                    return Some(format!(
                        "has a quaternion of length {norm:.4}: not a rotation"
                    ));
                }
            }
        }
        None => {}
    }
    match config {
        Config::Quadrants(cf) => {
            for (name, f) in ["cf1", "cf4", "cf6", "cfx"].iter().zip(cf) {
                if let Some(f) = f {
                    let v = f.value();
                    if !plausible_cf(v) {
                        return Some(format!(
                            "has {name} = {}: a configuration is a small integer",
                            shown(f.value())
                        ));
                    }
                }
            }
        }
        Config::StatusTurn { status, turn } => {
            if let Some(s) = status
                && s.value() > KUKA_STATUS_MAX
            {
                return Some(format!("has Status {}: only bits 0 to 4 exist", s.value()));
            }
            if let Some(t) = turn
                && t.value() > KUKA_TURN_MAX
            {
                return Some(format!("has Turn {}: only bits 0 to 5 exist", t.value()));
            }
        }
        Config::None => {}
    }
    None
}

/// Why a computed pose cannot be written (not finite, or beyond any robot cell), or `None`.
/// `words` are the target's language's.
pub(crate) fn implausible_result(p: &Position, new: &Pose, words: &Vocabulary) -> Option<Why> {
    let t = new.translation.vector;
    let q = new.rotation.coords;
    let what = describe(p);
    if !(t.iter().all(|v| v.is_finite()) && q.iter().all(|v| v.is_finite())) {
        return Some(Why::new(
            RefusalKind::ImplausibleResult,
            format!("{what}: the computed pose is not a finite number"),
            "check the profile and the cell file's base, track axis and frames for absurd values",
        ));
    }
    if (q.norm() - 1.0).abs() > 1e-6 {
        return Some(Why::new(
            RefusalKind::ImplausibleResult,
            format!("{what}: the computed orientation is not a rotation"),
            "check the profile and the cell file for absurd values",
        ));
    }
    if t.iter().any(|v| v.abs() > PLAUSIBLE_MM) {
        return Some(Why::new(
            RefusalKind::ImplausibleResult,
            format!(
                "{what}: the computed position lies more than 1 km from its {}'s origin",
                words.frame
            ),
            "check the profile and the cell file's base, track axis and frames for absurd values",
        ));
    }
    None
}

/// A written value in a message: plain, or with an exponent when huge (`1e22`, not 23 digits).
fn shown(v: f64) -> String {
    if v.is_finite() && v.abs() < 1e6 {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// The declared targets `call` offsets ([`OffsetCall::bases`]), decoded as `reading` says,
/// with their files.
///
/// [`OffsetCall::bases`]: crate::position::OffsetCall::bases
pub(crate) fn offset_bases<'p>(
    program: &'p Program,
    call: &crate::position::OffsetCall,
    reading: crate::position::Reading,
) -> Vec<(&'p ParsedFile, Position)> {
    let mut memo = crate::position::DecodeMemo::default();
    call.bases
        .iter()
        .filter_map(|&(fi, i)| {
            let f = program.files.get(fi)?;
            (i < f.positions.len()).then(|| {
                (
                    f,
                    f.positions.decoded_with(i, &f.source, reading, &mut memo),
                )
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::position::FrameDecl;
    use crate::syntax::Span;
    use crate::transform::test_support::{krl, rapid};

    /// The integer test of a configuration value is `is_finite && fract == 0 && |v| ≤ bound`,
    /// at the bound, either side of whole numbers, for -0, NaN and the infinities.
    #[test]
    fn plausible_cf_is_the_fract_test() {
        let fract_test = |v: f64| v.is_finite() && v.fract() == 0.0 && v.abs() <= PLAUSIBLE_CF;
        let mut values = vec![f64::NAN, f64::INFINITY, f64::NEG_INFINITY, 9e9, -9e9, 1e300];
        for whole in [0.0, 1.0, -1.0, 4.0, 999.0, 1000.0, 1001.0, -1000.0, -1001.0] {
            values.extend([whole, -whole, whole + 0.5, whole - 1e-9, whole + 1e-12]);
            values.push(f64::from_bits(whole.to_bits() + 1));
        }
        for v in values {
            assert_eq!(plausible_cf(v), fract_test(v), "{v:e}");
        }
    }

    /// A target used with two work objects names both; with three, all three, and says three.
    #[test]
    fn a_target_used_with_several_work_objects_names_them_all() {
        let program = rapid(
            "[[1,2,3],[1,0,0,0],[0,0,0,0],[100,9E9,9E9,9E9,9E9,9E9]]\n",
            "wA",
        );
        let file = &program.files[0];
        let mut p = file.position(0).unwrap();
        let message = |p: &Position| common_refusal(file, p).map(|w| w.message);
        p.usage.record(Some("wB"), None, false, 2);
        assert_eq!(
            message(&p).as_deref(),
            Some("robtarget `p1` is used with two work objects (`wA` and `wB`)")
        );
        p.usage.record(Some("wC"), None, false, 3);
        assert_eq!(
            message(&p).as_deref(),
            Some("robtarget `p1` is used with 3 work objects (`wA`, `wB` and `wC`)")
        );
    }

    /// A frame declaration `name` that a mechanical unit moves (`fixed`) or the robot holds.
    fn with_frame(mut program: Program, name: &str, kind: FrameKind, moved: bool) -> Program {
        let decl = FrameDecl {
            name: name.to_owned(),
            kind,
            span: Span::new(0, 0),
            line: 1,
            held_by_robot: Some(!moved),
            fixed: Some(!moved),
            moved_by: None,
            frame: None,
            oframe: None,
            scope: Default::default(),
            storage: Default::default(),
            assigned: false,
        };
        if let Some(f) = program.files.first_mut() {
            f.frames.push(decl);
        }
        program
    }

    fn refusal(program: &Program, name: &str) -> String {
        match resolve_frame(program, None, &BTreeMap::new(), name) {
            Err(why) => why.message,
            Ok(_) => panic!("`{name}` resolved"),
        }
    }

    #[test]
    fn the_last_work_object_is_what_resolving_it_again_gives() {
        // Runs of one work object, a change, world, a name that does not resolve, an unused
        // target, and back: each target's frame as resolved on its own.
        let line = "[[1,2,3],[1,0,0,0],[0,0,0,0],[0,9E9,9E9,9E9,9E9,9E9]]\n";
        let names = [
            Some("wobj_a"),
            Some("wobj_a"),
            Some("wobj_b"),
            Some("wobj_b"),
            Some("wobj0"),
            Some("nowhere"),
            None,
            Some("wobj_a"),
        ];
        let mut program = rapid(&line.repeat(names.len()), "wobj_a");
        for (u, name) in program.files[0].positions.usages_mut().zip(names) {
            *u = crate::position::Usage::default();
            if name.is_some() {
                u.record(name, Some("tool0"), false, 1);
            }
        }
        let frames = BTreeMap::from([
            (
                "wobj_a".to_owned(),
                crate::geometry::pose_xyz_deg(100.0, 0.0, 0.0, 0.0, 0.0, 0.0),
            ),
            (
                "wobj_b".to_owned(),
                crate::geometry::pose_xyz_deg(0.0, 200.0, 0.0, 0.0, 0.0, 90.0),
            ),
        ]);
        let last = LastWorkObject::default();
        let mut resolved = Vec::new();
        for p in program.files[0].positions() {
            let own = &program.files[0];
            let alone = work_object_of(&program, Some(own), &p, &frames, None);
            assert_eq!(last.work_object_of(&program, own, &p, &frames, None), alone);
            resolved.push(alone.is_ok());
        }
        assert_eq!(resolved, [true, true, true, true, true, false, false, true]);
    }

    #[test]
    fn a_refused_frame_is_named_in_the_words_of_its_language() {
        let kuka = |base: &str| krl("1 2 3 0 0 0 2 0 0\n", base);
        let abb = |wobj: &str| rapid("1 2 3 1 0 0 0 0 0 0 0 9E9 9E9 9E9 9E9 9E9 9E9\n", wobj);
        let cases = [
            (
                kuka("BASE_DATA[2]"),
                ("BASE_DATA[2]", FrameKind::Base, true),
                "base `BASE_DATA[2]` is moved by a mechanical unit (MACHINE_FRAME_DAT: an external kinematic)",
            ),
            (
                kuka("BASE_DATA[3]"),
                ("BASE_DATA[3]", FrameKind::Base, false),
                "base `BASE_DATA[3]` is held by the robot (IPO_FRAME #TCP: stationary tool)",
            ),
            (
                kuka("BASE_DATA[9]"),
                ("BASE_DATA[3]", FrameKind::Base, false),
                "base `BASE_DATA[9]` is not declared in the program",
            ),
            (
                abb("wStn"),
                ("wStn", FrameKind::WorkObject, true),
                "work object `wStn` is moved by a mechanical unit (ufprog FALSE)",
            ),
            (
                abb("wHeld"),
                ("wHeld", FrameKind::WorkObject, false),
                "work object `wHeld` is held by the robot (robhold TRUE: stationary tool)",
            ),
        ];
        for (program, (declared, kind, moved), want) in cases {
            let used = program.files[0]
                .position(0)
                .unwrap()
                .usage
                .wobj
                .clone()
                .unwrap();
            let program = with_frame(program, declared, kind, moved);
            assert_eq!(refusal(&program, &used), want);
        }
    }
}
