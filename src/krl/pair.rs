//! A KRL program is a `.src`/`.dat` pair: naming either file loads both.

use std::path::{Path, PathBuf};

use super::{analyse, config_dat, positions};
use crate::position::Program;
use crate::program::{LoadError, LoadOptions, read_source};

fn lower_ext(path: &Path) -> Option<String> {
    path.extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
}

/// The other file of `path`'s pair: same directory, same stem, `.dat` for a `.src` and back, in
/// any case (`Spot.SRC` pairs with `spot.dat`, an exact stem preferred). `None` for `.sub` files
/// and lone files.
pub fn partner_of(path: &Path) -> Option<PathBuf> {
    let want = match lower_ext(path)?.as_str() {
        "src" => "dat",
        "dat" => "src",
        _ => return None,
    };
    let stem = path.file_stem()?.to_str()?;
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_owned(),
        _ => PathBuf::from("."),
    };
    let mut found: Vec<(bool, PathBuf)> = std::fs::read_dir(&dir)
        .ok()?
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| {
            lower_ext(p).as_deref() == Some(want)
                && p.file_stem()
                    .and_then(|s| s.to_str())
                    .is_some_and(|s| s.eq_ignore_ascii_case(stem))
                && p.is_file()
        })
        .map(|p| {
            let exact = p.file_stem().and_then(|s| s.to_str()) == Some(stem);
            (!exact, p)
        })
        .collect();
    found.sort();
    let (_, p) = found.into_iter().next()?;
    // Keep the caller's spelling of the directory.
    Some(match (path.parent(), p.file_name()) {
        (Some(parent), Some(name)) => parent.join(name),
        _ => p,
    })
}

/// Loads the program `path` belongs to: naming the `.src` or the `.dat` loads both when both
/// exist (`.src` first); a lone file loads alone. With [`LoadOptions::krl_config_dat`], the
/// `$config.dat` is appended as the last file, carrying its `BASE_DATA`/`TOOL_DATA` frames
/// (its own positions, such as `XHOME`, are not part of the program and are dropped).
///
/// Bases and tools of every motion are resolved over the pair, so `.dat` positions carry the
/// usage of the `.src` motions that move to them.
pub fn load_program(path: &Path, options: &LoadOptions) -> Result<Program, LoadError> {
    let mut paths = vec![path.to_owned()];
    if let Some(other) = partner_of(path) {
        if lower_ext(path).as_deref() == Some("dat") {
            paths.insert(0, other);
        } else {
            paths.push(other);
        }
    }
    let mut files = Vec::new();
    let mut facts = Vec::new();
    for p in &paths {
        let (file, fact) = analyse(p, read_source(p)?);
        files.push(file);
        facts.push(fact);
    }
    positions::resolve(&mut files, &mut facts);
    if let Some(cfg) = &options.krl_config_dat {
        let mut file = config_dat::parse_config(cfg)?;
        file.positions.clear();
        files.push(file);
    }
    Ok(Program { files })
}
