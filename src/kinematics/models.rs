//! Bundled robot models (`model = "NAME"` in the cell file): published OPW parameter sets.
//!
//! Every entry says where its numbers come from. The joint maps (`offsets`, `signs`) are those
//! of the ROS-Industrial packages, whose joint values are the controller's (the ABB and KUKA
//! drivers pass them through unchanged), so `θ` here is what RAPID and KRL programs write.
//! Body-shop models without a published OPW set (ABB IRB 6640/6700/7600, …) are not guessed:
//! give their lengths in the cell file.

use super::opw::{Kinematics, OpwGeometry};

/// One bundled model.
#[derive(Clone, Copy, Debug)]
pub struct Model {
    /// The name the cell file uses, lower case.
    pub name: &'static str,
    /// What the robot is.
    pub title: &'static str,
    /// Where the geometry, joint map and limits come from.
    pub source: &'static str,
    geometry: OpwGeometry,
    offsets: [f64; 6],
    signs: [f64; 6],
    limits: [[f64; 2]; 6],
}

impl Model {
    /// The arm model: geometry, joint map and limits.
    pub fn kinematics(&self) -> Kinematics {
        Kinematics {
            geometry: self.geometry,
            offsets: self.offsets,
            signs: self.signs,
            limits: self.limits,
        }
    }
}

/// ROS-Industrial's KUKA map: A1, A4, A6 turn against the model's axes, A2 is −90° with the
/// upper arm upright.
const KUKA_SIGNS: [f64; 6] = [-1.0, 1.0, 1.0, -1.0, 1.0, -1.0];
const KUKA_OFFSETS: [f64; 6] = [0.0, -90.0, 0.0, 0.0, 0.0, 0.0];

/// Every bundled model, by `name` (the cell file's `model = "NAME"`).
pub const MODELS: &[Model] = &[
    Model {
        name: "abb_irb2400_10",
        title: "ABB IRB 2400/10",
        source: "geometry and offsets: opw_kinematics (Jmeyer1292/opw_kinematics, \
                 include/opw_kinematics/opw_parameters_examples.h, makeIrb2400_10) and \
                 shared/reference/README.md; limits: ROS-Industrial abb_irb2400_support \
                 urdf/irb2400_macro.xacro (axis 3 −60°…+65°)",
        geometry: OpwGeometry {
            a1: 100.0,
            a2: -135.0,
            b: 0.0,
            c1: 615.0,
            c2: 705.0,
            c3: 755.0,
            c4: 85.0,
        },
        offsets: [0.0, 0.0, -90.0, 0.0, 0.0, 0.0],
        signs: [1.0; 6],
        limits: [
            [-180.0, 180.0],
            [-100.0, 110.0],
            [-60.0, 65.0],
            [-200.0, 200.0],
            [-120.0, 120.0],
            [-400.0, 400.0],
        ],
    },
    Model {
        name: "abb_irb4600_40_255",
        title: "ABB IRB 4600-40/2.55",
        source: "derived from the joint origins and limits of ROS-Industrial abb_irb4600_support \
                 urdf/irb4600_40_255_macro.xacro (c1 = joint_1 z, a1 = joint_2 x, c2 = joint_3 z, \
                 a2 = −joint_4 z, c3 = joint_5 x, c4 = joint_6 x); the same values as \
                 rs-opw-kinematics `irb4600_40_255`",
        geometry: OpwGeometry {
            a1: 175.0,
            a2: -175.0,
            b: 0.0,
            c1: 495.0,
            c2: 1095.0,
            c3: 1270.0,
            c4: 135.0,
        },
        offsets: [0.0, 0.0, -90.0, 0.0, 0.0, 0.0],
        signs: [1.0; 6],
        limits: [
            [-180.0, 180.0],
            [-90.0, 150.0],
            [-180.0, 75.0],
            [-400.0, 400.0],
            [-125.0, 120.0],
            [-400.0, 400.0],
        ],
    },
    Model {
        name: "kuka_kr210_r3100_2",
        title: "KUKA KR 210 R3100-2 (KR QUANTEC)",
        source: "geometry and joint map: ROS-Industrial kuka_experimental \
                 kuka_kr210_support/config/opw_parameters_kr210_r3100-2.yaml; limits: \
                 kuka_kr210_support/urdf/kr210_r3100-2_macro.xacro",
        geometry: OpwGeometry {
            a1: 330.0,
            a2: -115.0,
            b: 0.0,
            c1: 645.0,
            c2: 1350.0,
            c3: 1420.0,
            c4: 240.0,
        },
        offsets: KUKA_OFFSETS,
        signs: KUKA_SIGNS,
        limits: [
            [-185.0, 185.0],
            [-140.0, -5.0],
            [-120.0, 168.0],
            [-350.0, 350.0],
            [-122.5, 122.5],
            [-350.0, 350.0],
        ],
    },
    Model {
        name: "kuka_kr6_r900_2",
        title: "KUKA KR 6 R900-2 (KR AGILUS)",
        source: "geometry and joint map: ROS-Industrial kuka_experimental \
                 kuka_kr6_support/config/opw_parameters_kr6r900_2.yaml; limits: \
                 kuka_kr6_support/urdf/kr6r900_2_macro.xacro",
        geometry: OpwGeometry {
            a1: 25.0,
            a2: -25.0,
            b: 0.0,
            c1: 400.0,
            c2: 455.0,
            c3: 420.0,
            c4: 90.0,
        },
        offsets: KUKA_OFFSETS,
        signs: KUKA_SIGNS,
        limits: [
            [-170.0, 170.0],
            [-190.0, 45.0],
            [-120.0, 156.0],
            [-185.0, 185.0],
            [-120.0, 120.0],
            [-350.0, 350.0],
        ],
    },
];

/// The bundled model `name` (any case; `-`, `/`, `.` and spaces read as `_`).
pub fn model(name: &str) -> Option<&'static Model> {
    let key: String = name
        .trim()
        .chars()
        .map(|c| match c {
            '-' | '/' | ' ' | '.' => '_',
            c => c.to_ascii_lowercase(),
        })
        .collect();
    MODELS.iter().find(|m| m.name == key)
}

/// The names of the bundled models.
pub fn model_names() -> Vec<&'static str> {
    MODELS.iter().map(|m| m.name).collect()
}
