//! The net itself: the faces between inside and outside voxels and the surface-nets node
//! placement ("Voxels" and "Node placement" in the module doc of [`super`]).

use super::{add, axis, Builder, Face, Grid, Idx};
use crate::implicit::Implicit;
use crate::polygonize::quad_net::QuadNet;
use crate::{Error, Result};
use nalgebra::{Point3, Vector3};
use rayon::prelude::*;

impl<I: Implicit + ?Sized> Builder<'_, I> {
    /// Faces between a known inside voxel and a known outside one (off-grid counts as outside),
    /// sorted.
    pub(super) fn faces(&self) -> Vec<Face> {
        let mut out: Vec<Face> = self
            .vox
            .iter()
            .filter(|(_, v)| v.inside)
            .flat_map(|(&k, _)| {
                let i = Grid::unkey(k);
                let mut fs = Vec::with_capacity(6);
                for a in 0..3 {
                    for pos in [true, false] {
                        let mut j = i;
                        j[a] += if pos { 1 } else { -1 };
                        let outside = match self.grid.key(j) {
                            None => true,
                            Some(nk) => self.vox.get(&nk).is_some_and(|w| !w.inside),
                        };
                        if outside {
                            fs.push((k, a, pos));
                        }
                    }
                }
                fs
            })
            .collect();
        out.sort_unstable();
        out
    }

    /// Corner grid vertices of a face, counter-clockwise seen from outside.
    pub(super) fn face_corners(face: &Face) -> [Idx; 4] {
        let (k, a, pos) = *face;
        let (b, c) = ((a + 1) % 3, (a + 2) % 3);
        let mut o = Grid::unkey(k);
        if pos {
            o[a] += 1;
        }
        let (eb, ec) = (axis(b), axis(c));
        let bc = add(eb, ec);
        // e_b x e_c = e_a: (o, o+eb, o+eb+ec, o+ec) faces +a; reversed faces -a.
        if pos {
            [o, add(o, eb), add(o, bc), add(o, ec)]
        } else {
            [o, add(o, ec), add(o, bc), add(o, eb)]
        }
    }

    pub(super) fn extract(&mut self) -> Result<QuadNet> {
        let faces = self.faces();
        if faces.is_empty() {
            return Err(Error::Degenerate(
                "the implicit has no inside voxel near the seeds: empty quad net".into(),
            ));
        }
        let corners: Vec<[u64; 4]> = faces
            .iter()
            .map(|f| Self::face_corners(f).map(Grid::vkey))
            .collect();
        let mut keys: Vec<u64> = corners.iter().flatten().copied().collect();
        keys.sort_unstable();
        keys.dedup();
        let index = |k: u64| keys.binary_search(&k).unwrap_or(0) as u32;
        let quads: Vec<[u32; 4]> = corners.iter().map(|c| c.map(index)).collect();
        // Surface-nets placement: every face's crossing on the segment between its voxels'
        // representatives, each node at the mean of its faces' crossings.
        let crossings: Vec<Option<Point3<f64>>> = faces
            .par_iter()
            .map(|&(k, a, pos)| {
                let vi = self.vox.get(&k)?;
                let mut j = Grid::unkey(k);
                j[a] += if pos { 1 } else { -1 };
                let (ro, fo) = match self.grid.key(j).and_then(|nk| self.vox.get(&nk)) {
                    Some(vo) => (vo.rep, vo.frep),
                    None => {
                        let c = self.grid.centre(j);
                        (c, self.f.value(&c))
                    }
                };
                segment_root(self.f, vi.rep, vi.frep, ro, fo, 1e-4 * self.grid.h)
            })
            .collect();
        let mut sum = vec![(Vector3::zeros(), 0usize); keys.len()];
        for (q, c) in quads.iter().zip(&crossings) {
            if let Some(c) = c {
                for &n in q {
                    sum[n as usize].0 += c.coords;
                    sum[n as usize].1 += 1;
                }
            }
        }
        // Nodes on both sheets of a part one voxel thick (opposite faces along one axis).
        let mut dirs = vec![0u8; keys.len()];
        for (q, &(_, a, pos)) in quads.iter().zip(&faces) {
            for &n in q {
                dirs[n as usize] |= 1 << (2 * a + usize::from(pos));
            }
        }
        self.stats.two_sheet_nodes = dirs
            .iter()
            .filter(|d| (0..3).any(|a| **d >> (2 * a) & 3 == 3))
            .count();
        self.node_vertex = keys.iter().map(|&k| Grid::unkey(k)).collect();
        let nodes = keys
            .iter()
            .zip(&sum)
            .map(|(&k, &(s, m))| {
                if m > 0 {
                    Point3::from(s / m as f64)
                } else {
                    let i = Grid::unkey(k);
                    self.grid.half_point([2 * i[0], 2 * i[1], 2 * i[2]])
                }
            })
            .collect();
        QuadNet::new(nodes, quads)
    }
}

/// A root of f on the segment a-b when f(a) < 0 < f(b) (Illinois regula falsi, to `tol` in
/// length); None when the ends do not bracket.
fn segment_root<I: Implicit + ?Sized>(
    f: &I,
    a: Point3<f64>,
    fa: f64,
    b: Point3<f64>,
    fb: f64,
    tol: f64,
) -> Option<Point3<f64>> {
    if !(fa < 0.0 && fb > 0.0 && fb.is_finite()) {
        return None;
    }
    let d = b - a;
    let len = d.norm();
    let (mut t0, mut f0, mut t1, mut f1) = (0.0, fa, 1.0, fb);
    let mut side = 0i8;
    for _ in 0..60 {
        let t = (t0 * f1 - t1 * f0) / (f1 - f0);
        let ft = f.value(&(a + d * t));
        if !ft.is_finite() {
            return None;
        }
        if ft == 0.0 || (t1 - t0) * len <= tol {
            return Some(a + d * t);
        }
        if ft < 0.0 {
            t0 = t;
            f0 = ft;
            if side == -1 {
                f1 *= 0.5;
            }
            side = -1;
        } else {
            t1 = t;
            f1 = ft;
            if side == 1 {
                f0 *= 0.5;
            }
            side = 1;
        }
        if (ft.abs() / len) < 1e-3 * tol {
            return Some(a + d * t);
        }
    }
    Some(a + d * (0.5 * (t0 + t1)))
}
