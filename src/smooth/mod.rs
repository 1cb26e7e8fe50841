//! Mesh smoothing passes, run on a triangle mesh in place:
//! - [`anisotropic()`]: feature-preserving anisotropic mean-curvature flow (seed 000 eq. 14-20,
//!   after Hildebrandt & Polthier 2004): removes scanner noise, keeps sharp edges and corners.
//! - [`arc()`]: circular-arc smoothing (seed 002 section 3.5, after Karbacher & Hausler): moves each
//!   vertex along its normal until it lies on circular arcs through its neighbours.
//! - [`centroid()`]: area-weighted centroid relaxation (seed 003 eq. 9, seed 000 eq. 13): improves
//!   triangle shapes, tangentially or with re-projection onto an implicit surface.
//!
//! All three share [`Control`] (region mask, progress callback) and return a [`SmoothReport`].
//! Build the mesh's [`Adjacency`] once and pass it to as many passes as needed:
//!
//! ```
//! use scansurf::mesh::Mesh;
//! use scansurf::smooth::{self, Adjacency, AnisotropicParams, Control};
//! use nalgebra::Point3;
//!
//! // A bent quad strip; any triangle mesh will do.
//! let mut mesh = Mesh {
//!     positions: (0..8)
//!         .map(|i| Point3::new((i / 2) as f64, (i % 2) as f64, ((i / 2) % 2) as f64 * 0.1))
//!         .collect(),
//!     normals: None,
//!     faces: (0..3u32)
//!         .flat_map(|k| [[2 * k, 2 * k + 2, 2 * k + 3], [2 * k, 2 * k + 3, 2 * k + 1]])
//!         .collect(),
//! };
//! let adj = Adjacency::build(&mesh)?;
//! // Smooth only vertex 2 and its one-ring, reporting progress.
//! let mut seed = vec![false; mesh.positions.len()];
//! seed[2] = true;
//! let region = adj.grow_rings(&seed, 1);
//! let progress = |done: usize, total: usize| eprintln!("{done}/{total}");
//! let control = Control { region: Some(&region), progress: Some(&progress) };
//! let report = smooth::anisotropic(&mut mesh, &adj, &AnisotropicParams::default(), &control)?;
//! assert_eq!(report.iterations, 15);
//! println!("{}", serde_json::to_string(&report).unwrap());
//! # Ok::<(), scansurf::Error>(())
//! ```
//! Every pass gathers per vertex (each new position is computed from the old mesh by one thread),
//! so the result does not depend on the number of threads; sums across the mesh are taken in a
//! fixed order. Memory is linear in the mesh.

pub mod anisotropic;
pub mod arc;
pub mod centroid;
mod common;
mod normal_filter;
#[cfg(test)]
pub(crate) mod testing;

pub use crate::mesh::adjacency::{vertices_of_faces, Adjacency};
pub use anisotropic::{anisotropic, AnisotropicParams};
pub use arc::{arc, ArcParams};
pub use centroid::{centroid, CentroidParams};
pub use common::{Control, SmoothReport};

/// One of the three passes with its parameters, for callers that choose at run time (the CLI's
/// `--method`).
#[derive(Debug, Clone, PartialEq)]
pub enum Method {
    /// [`anisotropic()`]: feature preserving, for scans of machined parts.
    Anisotropic(AnisotropicParams),
    /// [`arc()`]: circular arcs, for organic shapes.
    Arc(ArcParams),
    /// [`centroid()`]: triangle quality, with re-projection onto an implicit when one is given.
    Centroid(CentroidParams),
}

impl Method {
    /// The pass named `anisotropic`, `arc` or `centroid` with its default parameters.
    pub fn by_name(name: &str) -> crate::Result<Method> {
        match name {
            "anisotropic" => Ok(Method::Anisotropic(AnisotropicParams::default())),
            "arc" => Ok(Method::Arc(ArcParams::default())),
            "centroid" => Ok(Method::Centroid(CentroidParams::default())),
            _ => Err(crate::Error::InvalidOption(format!(
                "unknown smoothing method {name:?} (anisotropic, arc or centroid)"
            ))),
        }
    }

    /// Sets the number of iterations.
    pub fn with_iterations(mut self, n: usize) -> Method {
        match &mut self {
            Method::Anisotropic(p) => p.iterations = n,
            Method::Arc(p) => p.iterations = n,
            Method::Centroid(p) => p.iterations = n,
        }
        self
    }
}

/// Runs `method` on `mesh` in place. `surface`, when given, is what centroid relaxation projects
/// onto (the other passes ignore it).
pub fn run(
    mesh: &mut crate::mesh::Mesh,
    adj: &Adjacency,
    method: &Method,
    surface: Option<&dyn crate::implicit::Implicit>,
    control: &Control,
) -> crate::Result<SmoothReport> {
    match method {
        Method::Anisotropic(p) => anisotropic(mesh, adj, p, control),
        Method::Arc(p) => arc(mesh, adj, p, control),
        Method::Centroid(p) => centroid(mesh, adj, p, surface, control),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn methods_by_name() {
        let mut m = testing::sphere(2);
        let adj = Adjacency::build(&m).unwrap();
        for name in ["anisotropic", "arc", "centroid"] {
            let method = Method::by_name(name).unwrap().with_iterations(3);
            let rep = run(&mut m, &adj, &method, None, &Control::default()).unwrap();
            assert_eq!((rep.method, rep.iterations), (name, 3));
        }
        assert!(Method::by_name("taubin").is_err());
    }
}
