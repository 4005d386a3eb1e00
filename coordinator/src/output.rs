//! Output files: written whole or not at all (temporary file, then rename).

use std::path::Path;

use anyhow::Context;
use shared::geometry::Pose;

/// Write `bytes` to `path` atomically: a temporary file beside it, then a rename.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    let name = path
        .file_name()
        .with_context(|| format!("{}: not a file name", path.display()))?;
    let tmp = path.with_file_name(format!(
        ".{}.tmp-{}",
        name.to_string_lossy(),
        std::process::id()
    ));
    std::fs::write(&tmp, bytes).with_context(|| format!("writing {}", tmp.display()))?;
    std::fs::rename(&tmp, path).with_context(|| format!("renaming to {}", path.display()))?;
    Ok(())
}

/// The centre path as CSV: `step,x_m,y_m,heading_rad`, full precision.
pub fn path_csv(path: &[Pose]) -> anyhow::Result<Vec<u8>> {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(["step", "x_m", "y_m", "heading_rad"])?;
    for (step, p) in path.iter().enumerate() {
        w.write_record([
            step.to_string(),
            p.x_m.to_string(),
            p.y_m.to_string(),
            p.heading_rad.to_string(),
        ])?;
    }
    Ok(w.into_inner()?)
}
