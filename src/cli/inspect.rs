//! `scansurf inspect FILE [--json]`.

use crate::error::Result;
use std::path::PathBuf;

#[derive(Debug, clap::Args)]
pub struct Args {
    /// Mesh or point cloud (.ply .obj .stl .xyz .txt .pts .csv .e57 .las .laz).
    pub input: PathBuf,
    /// Print the report as JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

pub fn run(a: Args, _quiet: bool) -> Result<()> {
    let mesh = crate::io::read_mesh(&a.input)?;
    let mut report = crate::inspect::inspect(&a.input.display().to_string(), &mesh);
    report.scans = crate::io::scan_info(&a.input)?.map(|i| i.scans);
    if a.json {
        let s = serde_json::to_string_pretty(&report)
            .map_err(|e| crate::Error::Numerical(format!("cannot serialize report: {e}")))?;
        println!("{s}");
    } else {
        print!("{}", report.to_text());
    }
    Ok(())
}
