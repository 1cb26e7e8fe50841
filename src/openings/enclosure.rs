//! Do the points enclose a volume? A ray test on the oriented points, before any fitting.
//!
//! From a point p with outward normal n, the ray p - t n (t > 0) runs into the material. If the
//! points sample the whole boundary of a solid, the ray meets the boundary again from inside:
//! points whose normals point along the ray, n_q . (-n) > 0. Where a side was not scanned (the
//! underside of a part on a table, the back of a face), rays from the opposite side leave the
//! bounding box without meeting anything. The *escape share*
//!
//! ```text
//! e = #{rays that leave the box without a hit} / #rays
//! ```
//!
//! is about the share of the surface that looks into an opening: the bunny's small base holes
//! let few rays out, a block without its bottom the rays of its top and of its slots' floors (a
//! third of them), a face scanned from the front nearly all.
//!
//! The rays march through an occupancy grid (cells of a [`CELLS`]-th of the bounding box's
//! longest side, at least two point spacings) in which each cell keeps a bit per direction class of its points'
//! normals (the 26 directions of the cell's neighbours); the cells are dilated by one so that a
//! ray cannot pass between two diagonal neighbours of a sampled surface. A cell is a hit when
//! one of its directions lies within 60 degrees of the ray. Rays start from [`RAYS`] points
//! evenly spread through the input order (deterministic).
//! This costs milliseconds and runs before the implicit, so that `auto` is decided before the
//! expensive work (issue 34: an open scan used to fail after a minute).

use crate::mesh::Aabb;
use nalgebra::{Point3, Vector3};
use rayon::prelude::*;

/// Grid cells along the bounding box's longest side.
pub const CELLS: usize = 128;
/// Rays cast (at most; one per point on smaller inputs).
pub const RAYS: usize = 4096;
/// A ray hits a cell with a normal direction within this angle's cosine of the ray.
const HIT_COS: f64 = 0.2;

/// Result of [`escape_share`].
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Enclosure {
    pub rays: usize,
    pub escaped: usize,
    /// escaped / rays.
    pub escape_share: f64,
}

/// The 26 unit directions to a cell's neighbours.
fn directions() -> Vec<Vector3<f64>> {
    let mut d = Vec::with_capacity(26);
    for m in 0..27 {
        if m == 13 {
            continue;
        }
        let v = Vector3::new(
            (m % 3) as f64 - 1.0,
            (m / 3 % 3) as f64 - 1.0,
            (m / 9) as f64 - 1.0,
        );
        d.push(v.normalize());
    }
    d
}

/// The occupancy grid: per cell a bit mask of the direction classes of its points' normals.
struct Grid {
    min: Point3<f64>,
    cell: f64,
    dims: [usize; 3],
    masks: Vec<u32>,
}

impl Grid {
    fn index(&self, c: [i64; 3]) -> Option<usize> {
        if (0..3).all(|k| c[k] >= 0 && (c[k] as usize) < self.dims[k]) {
            Some((c[2] as usize * self.dims[1] + c[1] as usize) * self.dims[0] + c[0] as usize)
        } else {
            None
        }
    }
    fn cell_of(&self, p: &Point3<f64>) -> [i64; 3] {
        let r = (p - self.min) / self.cell;
        [r.x.floor() as i64, r.y.floor() as i64, r.z.floor() as i64]
    }
}

/// The escape share of rays cast inward from the oriented points (see the module doc).
pub fn escape_share(points: &[Point3<f64>], normals: &[Vector3<f64>]) -> Enclosure {
    escape_share_with_spacing(points, normals, spacing_of(points))
}

/// The points' spacing (mean distance to their nearest neighbours, on a sample of at most
/// [`RAYS`] points): cells must be at least two spacings wide, or rays pass between the
/// points of a sparse cloud (spot's 2,930 vertices as a cloud: escape share 15 % with cells of
/// a 128th, 0.3 % with cells of two spacings).
fn spacing_of(points: &[Point3<f64>]) -> f64 {
    let Ok(kd) = crate::spatial::KdTree::build(points) else {
        return 0.0;
    };
    let step = (points.len() / RAYS).max(1);
    let d: Vec<f64> = points
        .par_iter()
        .step_by(step)
        .map(|p| kd.knn(p, 2).last().map_or(0.0, |x| x.1))
        .collect();
    if d.is_empty() {
        0.0
    } else {
        d.iter().sum::<f64>() / d.len() as f64
    }
}

/// [`escape_share`] with the points' spacing given (cells at least `2 spacing` wide).
pub fn escape_share_with_spacing(
    points: &[Point3<f64>],
    normals: &[Vector3<f64>],
    spacing: f64,
) -> Enclosure {
    let none = Enclosure {
        rays: 0,
        escaped: 0,
        escape_share: 0.0,
    };
    let Some(b) = Aabb::of(points) else {
        return none;
    };
    let ext = b.max - b.min;
    let longest = ext.x.max(ext.y).max(ext.z);
    if !(longest > 0.0 && longest.is_finite()) {
        return none;
    }
    let cell = (longest / CELLS as f64).max(2.0 * spacing);
    // Two cells of margin: rays leave through empty cells.
    let min = b.min - Vector3::repeat(2.0 * cell);
    let dims = [ext.x, ext.y, ext.z].map(|e| (e / cell).ceil() as usize + 5);
    let dirs = directions();
    let mut raw = Grid {
        min,
        cell,
        dims,
        masks: vec![0u32; dims[0] * dims[1] * dims[2]],
    };
    for (p, n) in points.iter().zip(normals) {
        let Some(i) = raw.index(raw.cell_of(p)) else {
            continue;
        };
        let best = (0..dirs.len())
            .max_by(|&a, &b| dirs[a].dot(n).total_cmp(&dirs[b].dot(n)))
            .unwrap_or(0);
        raw.masks[i] |= 1 << best;
    }
    // Dilation by one cell (26-neighbourhood).
    let mut masks = vec![0u32; raw.masks.len()];
    for z in 0..dims[2] as i64 {
        for y in 0..dims[1] as i64 {
            for x in 0..dims[0] as i64 {
                let Some(i) = raw.index([x, y, z]) else {
                    continue;
                };
                let m = raw.masks[i];
                if m == 0 {
                    continue;
                }
                for d in 0..27i64 {
                    let c = [x + d % 3 - 1, y + d / 3 % 3 - 1, z + d / 9 - 1];
                    if let Some(j) = raw.index(c) {
                        masks[j] |= m;
                    }
                }
            }
        }
    }
    let grid = Grid { masks, ..raw };
    let rays = points.len().min(RAYS);
    if rays == 0 {
        return none;
    }
    let stride = points.len() as f64 / rays as f64;
    let escaped = (0..rays)
        .into_par_iter()
        .filter(|&r| {
            let i = ((r as f64 + 0.5) * stride) as usize;
            let i = i.min(points.len() - 1);
            match normals[i].try_normalize(0.0) {
                Some(n) => escapes(&grid, &dirs, &points[i], &-n),
                None => false,
            }
        })
        .count();
    Enclosure {
        rays,
        escaped,
        escape_share: escaped as f64 / rays as f64,
    }
}

/// Whether the ray from `p` along unit `d` leaves the grid without entering a cell that holds
/// a normal within 60 degrees of `d`. Steps of half a cell. The start cell counts: the
/// points around `p` face away from the ray, and the far side of a part thinner than a cell
/// faces along it.
fn escapes(grid: &Grid, dirs: &[Vector3<f64>], p: &Point3<f64>, d: &Vector3<f64>) -> bool {
    let hit_bits: u32 = dirs
        .iter()
        .enumerate()
        .filter(|(_, b)| b.dot(d) > HIT_COS)
        .fold(0, |m, (k, _)| m | (1 << k));
    let step = 0.5 * grid.cell;
    let mut t = step;
    loop {
        let q = p + d * t;
        let c = grid.cell_of(&q);
        let Some(i) = grid.index(c) else {
            return true;
        };
        if grid.masks[i] & hit_bits != 0 {
            return false;
        }
        t += step;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Points on the unit sphere (Fibonacci), outward normals; `keep` filters them.
    fn sphere(
        n: usize,
        keep: impl Fn(&Point3<f64>) -> bool,
    ) -> (Vec<Point3<f64>>, Vec<Vector3<f64>>) {
        let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
        let (mut p, mut nr) = (Vec::new(), Vec::new());
        for i in 0..n {
            let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
            let r = (1.0 - z * z).sqrt();
            let a = golden * i as f64;
            let v = Vector3::new(r * a.cos(), r * a.sin(), z);
            if keep(&Point3::from(v)) {
                p.push(Point3::from(v));
                nr.push(v);
            }
        }
        (p, nr)
    }

    #[test]
    fn closed_sphere_encloses_and_a_cap_does_not() {
        let (p, n) = sphere(60_000, |_| true);
        let e = escape_share(&p, &n);
        assert_eq!(e.rays, RAYS);
        assert!(e.escape_share < 0.01, "{e:?}");
        // A small hole (a cap of 10 degrees) lets few rays out.
        let (p, n) = sphere(60_000, |q| q.z < 0.985);
        assert!(escape_share(&p, &n).escape_share < 0.05);
        // The upper half: the rays of the upper half run out through the missing lower half.
        let (p, n) = sphere(60_000, |q| q.z > 0.0);
        let e = escape_share(&p, &n);
        assert!(e.escape_share > 0.8, "{e:?}");
        // Normals flipped inward: every ray runs out.
        let (p, n) = sphere(20_000, |_| true);
        let n: Vec<_> = n.iter().map(|v| -v).collect();
        assert!(escape_share(&p, &n).escape_share > 0.95);
        // Nothing to look at.
        assert_eq!(escape_share(&[], &[]).rays, 0);
    }
}
