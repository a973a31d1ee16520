//! Where transformed files go: the output layer lives in [`crate::output`]; these names stay
//! here for the transform commands.

pub use crate::output::{
    Destination, FileWrite as PlannedWrite, OutputError, Roots, backup_path, output_path,
    output_path_under, plan, plan_writes, unified_diff, write_all,
};
