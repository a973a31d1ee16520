//! `rust-version` in Cargo.toml is what the locked dependencies really need: no toolchain other
//! than the current one is at hand, so the check compares the declared minimum against the
//! largest `rust-version` any locked package (normal, build or dev) declares. Crates without a
//! `rust-version` state nothing and are not counted.

use std::process::Command;

use crate::support::root;

fn version(text: &str) -> Vec<u64> {
    let mut v: Vec<u64> = text.split('.').map(|p| p.parse().unwrap_or(0)).collect();
    v.resize(3, 0);
    v
}

#[test]
fn rust_version_is_the_largest_of_the_locked_dependencies() {
    let out = Command::new(env!("CARGO"))
        .args([
            "metadata",
            "--format-version",
            "1",
            "--locked",
            "--offline",
            "--filter-platform",
            "x86_64-unknown-linux-gnu",
        ])
        .current_dir(root())
        .output()
        .expect("cargo runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let meta: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let resolved: Vec<&str> = meta["resolve"]["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|n| n["id"].as_str())
        .collect();
    let mut ours = None;
    let mut needed: (Vec<u64>, String) = (vec![0, 0, 0], String::new());
    for p in meta["packages"].as_array().unwrap() {
        let (Some(id), Some(name)) = (p["id"].as_str(), p["name"].as_str()) else {
            continue;
        };
        let Some(rv) = p["rust_version"].as_str() else {
            continue;
        };
        if name == "trackfix" {
            ours = Some(version(rv));
        } else if resolved.contains(&id) && version(rv) > needed.0 {
            needed = (version(rv), format!("{name} {}", p["version"]));
        }
    }
    let ours = ours.expect("Cargo.toml declares rust-version");
    assert_eq!(
        ours, needed.0,
        "Cargo.toml's rust-version should be the locked dependencies' largest ({})",
        needed.1
    );
}
