//! A KRL program is a `.src`/`.dat` pair: naming either file loads both.

use std::path::{Path, PathBuf};

use super::{analyse, resolve};
use crate::output::InputBytes;
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
    let mut sources = Vec::with_capacity(paths.len());
    for p in paths {
        let bytes = read_source(&p, options)?;
        sources.push((p, bytes));
    }
    load_program_from_sources(sources, options)
}

/// Builds a program from files already in memory (a `.src` and its `.dat`, or a lone file;
/// a path whose name is `$config.dat`, in any case, is taken as the cell's configuration), with
/// the same base/tool resolution as [`load_program`]: `transfer` re-parses a transformed pair
/// this way without writing it out. Paths are names only: nothing is read from disk except
/// [`LoadOptions::krl_config_dat`] when given (which then replaces an in-memory one), so the
/// only error is failing to read that file. Bytes that are not KRL are kept verbatim and
/// reported in each file's diagnostics.
///
/// Files keep their given order, except that a `.src` is placed before a `.dat` and a
/// `$config.dat` last, as [`load_program`] orders them.
pub fn load_program_from_sources<S: Into<InputBytes>>(
    files: Vec<(PathBuf, S)>,
    options: &LoadOptions,
) -> Result<Program, LoadError> {
    let is_config = |p: &Path| {
        p.file_name()
            .and_then(|n| n.to_str())
            .is_some_and(|n| n.eq_ignore_ascii_case("$config.dat"))
    };
    let rank = |p: &Path| {
        if is_config(p) {
            2
        } else if lower_ext(p).as_deref() == Some("dat") {
            1
        } else {
            0
        }
    };
    let mut files = files;
    files.sort_by_key(|(p, _)| rank(p));
    let mut program_files = Vec::new();
    let mut facts = Vec::new();
    let mut configs = 0;
    let own_config = options.krl_config_dat.is_none();
    for (path, bytes) in files {
        let config = is_config(&path);
        if config && !own_config {
            continue;
        }
        configs += usize::from(config);
        let (file, fact) = analyse(&path, bytes.into());
        program_files.push(file);
        facts.push(fact);
    }
    // A `$config.dat` among the files is resolved with them: its global points (`DECL E6POS
    // XPICK={…}`) carry the usage of the motions that move to them. The cell's gives the
    // declared values of the bases and tools the program assigns.
    let cell_config = match &options.krl_config_dat {
        Some(cfg) => Some(options.config_dat.get(cfg)?),
        None => None,
    };
    let declared = cell_config
        .as_ref()
        .map_or(&[][..], |c| c.frames.as_slice());
    resolve::resolve(&mut program_files, &mut facts, declared);
    for file in program_files.iter_mut().rev().take(configs) {
        keep_used_points(file);
    }
    program_files.extend(cell_config);
    Ok(Program {
        files: program_files,
    })
}

/// Of a `$config.dat` resolved with a program, only the Cartesian points a motion of the program
/// uses are the program's (`XHOME` and the points other programs move to are not).
fn keep_used_points(file: &mut crate::position::ParsedFile) {
    file.positions.retain(&file.source, |p| {
        p.cartesian.is_some() && !p.usage.lines.is_empty()
    });
}
