//! File formats: one reader/writer per format, chosen by extension (and, for STL, content).
//!
//! Every reader returns a [`Mesh`] (a point cloud when it has no faces) or an [`Error`] that
//! names the file and, for syntax errors, the line (text) or byte offset (binary). Readers
//! check every coordinate for NaN/infinity and every face index against the vertex count.
//! Every writer goes through [`atomic::write_atomic`]: a temporary file in the target's
//! directory, renamed over the target only when complete.

pub mod atomic;
pub mod e57;
pub mod las;
pub mod obj;
pub mod ply;
pub mod step;
pub mod stl;
pub mod text;
pub mod xyz;

use crate::error::{Error, Result};
use crate::mesh::Mesh;
use std::path::Path;

pub use atomic::write_atomic;

/// The formats scansurf reads and writes meshes and clouds in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    Ply,
    Obj,
    Stl,
    /// Whitespace- or comma-separated points `x y z [nx ny nz]`: `.xyz`, `.txt`, `.pts`, `.csv`.
    Xyz,
    /// E57 scanner files (read only): all scans merged, poses applied.
    E57,
    /// ASPRS LAS and LASzip LAZ (read only).
    Las,
}

impl Format {
    /// The format a path's extension names.
    pub fn from_path(path: &Path) -> Result<Format> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase())
            .unwrap_or_default();
        match ext.as_str() {
            "ply" => Ok(Format::Ply),
            "obj" => Ok(Format::Obj),
            "stl" => Ok(Format::Stl),
            "xyz" | "txt" | "pts" | "csv" | "asc" => Ok(Format::Xyz),
            "e57" => Ok(Format::E57),
            "las" | "laz" => Ok(Format::Las),
            "" => Err(Error::unsupported(
                path,
                "no file extension; expected .ply, .obj, .stl, .xyz, .txt, .pts, .csv, .e57, .las or .laz",
            )),
            other => Err(Error::unsupported(
                path,
                format!(
                    "unknown extension '.{other}'; expected .ply, .obj, .stl, .xyz, .txt, .pts, .csv, .e57, .las or .laz"
                ),
            )),
        }
    }
}

/// Options for writing meshes.
#[derive(Debug, Clone, Copy, Default)]
pub struct WriteOptions {
    /// Write PLY and STL as text instead of binary.
    pub ascii: bool,
}

/// Reads the whole file, with errors that name it (missing, a directory, unreadable, empty).
pub fn read_bytes(path: &Path) -> Result<Vec<u8>> {
    let meta = std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
    if meta.is_dir() {
        return Err(Error::content(path, "is a directory, not a file"));
    }
    // The bytes plus the mesh parsed from them: at most about twice the file (a binary float
    // becomes an f64; text is longer than the numbers it holds).
    crate::limits::check(
        "reading this file",
        3.0 * meta.len() as f64,
        "use a machine with more memory or raise --max-memory",
    )
    .map_err(|e| Error::content(path, e.to_string()))?;
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    if bytes.is_empty() {
        return Err(Error::content(path, "file is empty"));
    }
    Ok(bytes)
}

/// Fails unless `path` is a non-empty regular file (for readers that stream).
pub(crate) fn check_nonempty_file(path: &Path) -> Result<()> {
    let meta = std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
    if meta.is_dir() {
        return Err(Error::content(path, "is a directory, not a file"));
    }
    if meta.len() == 0 {
        return Err(Error::content(path, "file is empty"));
    }
    Ok(())
}

/// Scanner-file facts that a plain point list lacks, for `inspect`.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ScanInfo {
    /// Number of scans (E57 point clouds; 1 for LAS/LAZ).
    pub scans: usize,
    /// Points the file declares (E57 counts invalid ones too).
    pub declared_points: u64,
}

/// Scan count and declared points of an E57 or LAS/LAZ file; `None` for other formats.
pub fn scan_info(path: &Path) -> Result<Option<ScanInfo>> {
    match Format::from_path(path)? {
        Format::E57 => {
            let i = e57::info(path)?;
            Ok(Some(ScanInfo {
                scans: i.scans,
                declared_points: i.points,
            }))
        }
        Format::Las => {
            let i = las::info(path)?;
            Ok(Some(ScanInfo {
                scans: 1,
                declared_points: i.points,
            }))
        }
        _ => Ok(None),
    }
}

/// Reads a mesh or point cloud, choosing the reader by extension.
pub fn read_mesh(path: &Path) -> Result<Mesh> {
    // Existence and kind first, so a missing file or a directory is named as such.
    let meta = std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
    if meta.is_dir() {
        return Err(Error::content(path, "is a directory, not a file"));
    }
    let format = Format::from_path(path)?;
    let mesh = match format {
        // Scanner files can be gigabytes: their readers stream from the file.
        Format::E57 => e57::read(path)?,
        Format::Las => las::read(path)?,
        _ => {
            let bytes = read_bytes(path)?;
            match format {
                Format::Ply => ply::parse(path, &bytes)?,
                Format::Obj => obj::parse(path, &bytes)?,
                Format::Stl => stl::parse(path, &bytes)?,
                _ => xyz::parse(path, &bytes)?,
            }
        }
    };
    validate(path, &mesh)?;
    Ok(mesh)
}

/// Writes a mesh or point cloud in the format the extension names, atomically.
pub fn write_mesh(path: &Path, mesh: &Mesh, options: WriteOptions) -> Result<()> {
    let format = Format::from_path(path)?;
    if matches!(format, Format::E57 | Format::Las) {
        return Err(Error::unsupported(
            path,
            "scansurf reads E57 and LAS/LAZ but does not write them; write .ply or .xyz",
        ));
    }
    if format == Format::Stl && mesh.faces.is_empty() {
        return Err(Error::unsupported(
            path,
            "STL holds triangles only; write a point cloud as .ply, .obj or .xyz",
        ));
    }
    write_atomic(path, |w| match format {
        Format::Ply => ply::write(w, mesh, options.ascii),
        Format::Obj => obj::write(w, mesh),
        Format::Stl => stl::write(w, mesh, options.ascii),
        _ => xyz::write(w, mesh),
    })
}

/// Checks what every reader guarantees: finite coordinates and normals, face indices in range.
pub fn validate(path: &Path, mesh: &Mesh) -> Result<()> {
    if let Some(i) = mesh
        .positions
        .iter()
        .position(|p| !p.iter().all(|c| c.is_finite()))
    {
        let p = mesh.positions[i];
        return Err(Error::content(
            path,
            format!(
                "vertex {} has a non-finite coordinate ({}, {}, {})",
                i + 1,
                p.x,
                p.y,
                p.z
            ),
        ));
    }
    if let Some(n) = &mesh.normals {
        if n.len() != mesh.positions.len() {
            return Err(Error::content(
                path,
                format!("{} normals for {} vertices", n.len(), mesh.positions.len()),
            ));
        }
        if let Some(i) = n.iter().position(|v| !v.iter().all(|c| c.is_finite())) {
            return Err(Error::content(
                path,
                format!("normal of vertex {} is not finite", i + 1),
            ));
        }
    }
    let nv = mesh.positions.len();
    if let Some((fi, f)) = mesh
        .faces
        .iter()
        .enumerate()
        .find(|(_, f)| f.iter().any(|&v| v as usize >= nv))
    {
        let bad = f.iter().find(|&&v| v as usize >= nv).copied().unwrap_or(0);
        return Err(Error::content(
            path,
            format!(
                "face {} uses vertex index {} but the file has only {} vertices",
                fi + 1,
                bad,
                nv
            ),
        ));
    }
    Ok(())
}

/// Builds a face list from polygons by fan triangulation.
pub(crate) fn push_polygon(faces: &mut Vec<[u32; 3]>, poly: &[u32]) {
    for k in 1..poly.len().saturating_sub(1) {
        faces.push([poly[0], poly[k], poly[k + 1]]);
    }
}
