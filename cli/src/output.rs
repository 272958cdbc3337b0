//! Output files of the command line: never an input, never another output of the same run, and
//! never half written (each is written to a temporary file beside it, then renamed; not
//! renamed, and removed, on an error or after SIGINT or SIGTERM).

use anyhow::{Context, Result, bail};
use std::path::{Path, PathBuf};

/// The absolute, normalised form of `p` (its parent resolved through symbolic links when it
/// exists), to compare paths that name the same file differently.
fn normalised(p: &Path) -> PathBuf {
    if let Ok(c) = p.canonicalize() {
        return c;
    }
    let abs = std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
    match (abs.parent(), abs.file_name()) {
        (Some(dir), Some(name)) => dir
            .canonicalize()
            .map(|d| d.join(name))
            .unwrap_or_else(|_| abs.clone()),
        _ => abs,
    }
}

/// An error if an output path is also an input path or another output path.
pub fn check_distinct(inputs: &[(&str, &Path)], outputs: &[(&str, &Path)]) -> Result<()> {
    for (i, (what, out)) in outputs.iter().enumerate() {
        let o = normalised(out);
        for (iw, inp) in inputs {
            if normalised(inp) == o {
                bail!(
                    "the {what} output {} is the {iw} input: it would be overwritten",
                    out.display()
                );
            }
        }
        for (w2, out2) in &outputs[..i] {
            if normalised(out2) == o {
                bail!(
                    "the {what} and {w2} outputs are the same file {}",
                    out.display()
                );
            }
        }
    }
    Ok(())
}

/// Writes `path` through `write` (given a temporary path in the same directory), then renames
/// the temporary file to `path`; on failure the temporary file is removed and `path` is left
/// as it was.
pub fn atomic(path: &Path, write: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    let name = path
        .file_name()
        .with_context(|| format!("{} is not a file path", path.display()))?;
    let mut tmp_name = std::ffi::OsString::from(".");
    tmp_name.push(name);
    tmp_name.push(format!(".tmp-{}", std::process::id()));
    let tmp = path.with_file_name(tmp_name);
    // keep the extension last: writers choose the format by extension
    let tmp = match path.extension() {
        Some(ext) => tmp.with_extension(format!(
            "{}.{}",
            tmp.extension().and_then(|e| e.to_str()).unwrap_or("tmp"),
            ext.to_string_lossy()
        )),
        None => tmp,
    };
    // an interrupted run (SIGINT, SIGTERM) puts no output in place
    let result = write(&tmp)
        .and_then(|()| Ok(crate::interrupt::check()?))
        .and_then(|()| {
            std::fs::rename(&tmp, path)
                .with_context(|| format!("renaming {} to {}", tmp.display(), path.display()))
        });
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn outputs_must_differ_from_inputs_and_each_other() {
        let dir = std::env::temp_dir().join(format!("gradvi-output-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mesh = dir.join("m.msh");
        std::fs::write(&mesh, "x").unwrap();
        let same = dir.join(".").join("m.msh");
        assert!(check_distinct(&[("mesh", &mesh)], &[("VTU", &same)]).is_err());
        let a = dir.join("a.vtu");
        assert!(check_distinct(&[("mesh", &mesh)], &[("VTU", &a), ("JSON", &a)]).is_err());
        let b = dir.join("b.json");
        assert!(check_distinct(&[("mesh", &mesh)], &[("VTU", &a), ("JSON", &b)]).is_ok());
        // a failed write leaves nothing behind and the old file intact
        std::fs::write(&a, "old").unwrap();
        assert!(
            atomic(&a, |tmp| {
                std::fs::write(tmp, "half")?;
                bail!("failed")
            })
            .is_err()
        );
        assert_eq!(std::fs::read_to_string(&a).unwrap(), "old");
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 2);
        atomic(&a, |tmp| Ok(std::fs::write(tmp, "new")?)).unwrap();
        assert_eq!(std::fs::read_to_string(&a).unwrap(), "new");
        std::fs::remove_dir_all(&dir).ok();
    }
}
