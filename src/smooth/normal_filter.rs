//! Bilateral filtering of face normals (after Zheng, Fu, Au, Tai 2011, "Bilateral normal filtering
//! for mesh denoising"), used by [`super::anisotropic`] to tell features from noise.
//!
//! One pass replaces each face normal by
//!
//!   m_f = normalize( sum_{g in ring(f)} A_g W(|n_f - n_g|) n_g ),  W(d) = 1 / (1 + d^2 / sigma^2),
//!
//! over the faces sharing a vertex with f, A_g the face area. The ring is walked through the
//! vertex -> faces adjacency without building a face ring: a face sharing an edge with f is met
//! twice and f itself three times, which stands in for the original's spatial Gaussian (within
//! one ring that Gaussian is nearly constant anyway). Normals across a sharp edge differ by far
//! more than sigma and barely mix; noise, whose normals scatter by less, averages out. The Cauchy
//! range weight W replaces the Gaussian:
//! the same shape near zero, a heavier tail, and no exponential (this runs on every face,
//! several times per smoothing iteration).

use crate::mesh::adjacency::Adjacency;
use nalgebra::Vector3;
use rayon::prelude::*;

/// A filtered unit face normal and the face's area, packed in `f32` so that one 16-byte load
/// brings both (the filter reads every face's ring twice per pass; `f32` is ample for a weight).
pub(crate) type PackedNormal = [f32; 4];

/// `passes` bilateral passes over the unit face normals `normals` (zero for degenerate faces,
/// which neither receive nor give), weighted by `areas`; the result in `out` as
/// `[nx, ny, nz, area]`.
pub(crate) fn filter_normals(
    faces: &[[u32; 3]],
    adj: &Adjacency,
    areas: &[f64],
    normals: &[Vector3<f64>],
    sigma: f64,
    passes: usize,
    out: &mut Vec<PackedNormal>,
) {
    normals
        .par_iter()
        .zip(areas)
        .map(|(n, &a)| [n.x as f32, n.y as f32, n.z as f32, a as f32])
        .collect_into_vec(out);
    if passes == 0 || sigma.is_nan() || sigma <= 0.0 {
        return;
    }
    let inv_s2 = (1.0 / (sigma * sigma)) as f32;
    let mut tmp: Vec<PackedNormal> = Vec::with_capacity(normals.len());
    for _ in 0..passes {
        let cur: &[PackedNormal] = out;
        (0..cur.len())
            .into_par_iter()
            .map(|f| {
                let nf = cur[f];
                if nf[0] == 0.0 && nf[1] == 0.0 && nf[2] == 0.0 {
                    return nf;
                }
                let mut s = [0f32; 3];
                for &v in &faces[f] {
                    for &g in adj.faces_of_vertex(v as usize) {
                        let ng = cur[g as usize];
                        let d = [nf[0] - ng[0], nf[1] - ng[1], nf[2] - ng[2]];
                        let d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
                        let w = ng[3] / (1.0 + d2 * inv_s2);
                        s[0] += w * ng[0];
                        s[1] += w * ng[1];
                        s[2] += w * ng[2];
                    }
                }
                let l = (s[0] * s[0] + s[1] * s[1] + s[2] * s[2]).sqrt();
                if l > 0.0 && l.is_finite() {
                    [s[0] / l, s[1] / l, s[2] / l, nf[3]]
                } else {
                    nf
                }
            })
            .collect_into_vec(&mut tmp);
        std::mem::swap(out, &mut tmp);
    }
}

/// The normal part of a packed normal, in `f64`.
pub(crate) fn unpack(p: &PackedNormal) -> Vector3<f64> {
    Vector3::new(p[0] as f64, p[1] as f64, p[2] as f64)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::Mesh;
    use nalgebra::Point3;

    #[test]
    fn keeps_a_crease_and_averages_noise() {
        // A roof: two planes meeting at x = 0 at 90 degrees, 5 x 5 vertices per side, with one
        // face normal perturbed by 20 degrees.
        let mut positions = Vec::new();
        for j in 0..5 {
            for i in 0..9 {
                let x = i as f64 - 4.0;
                positions.push(Point3::new(x, j as f64, -x.abs()));
            }
        }
        let mut faces = Vec::new();
        for j in 0..4u32 {
            for i in 0..8u32 {
                let a = j * 9 + i;
                faces.push([a, a + 1, a + 10]);
                faces.push([a, a + 10, a + 9]);
            }
        }
        let m = Mesh {
            positions,
            normals: None,
            faces,
        };
        let adj = Adjacency::build(&m).unwrap();
        let clean: Vec<Vector3<f64>> = (0..m.faces.len())
            .map(|f| m.face_cross(f).normalize())
            .collect();
        let areas: Vec<f64> = (0..m.faces.len()).map(|f| m.face_area(f)).collect();
        let mut noisy = clean.clone();
        let k = 2 * (8 + 2); // a face on the left side, away from the crease
        noisy[k] = (clean[k] + Vector3::new(0.0, 0.36, 0.0)).normalize();
        let mut out = Vec::new();
        filter_normals(&m.faces, &adj, &areas, &noisy, 0.35, 3, &mut out);
        let out: Vec<Vector3<f64>> = out.iter().map(unpack).collect();
        let ang =
            |a: &Vector3<f64>, b: &Vector3<f64>| a.dot(b).clamp(-1.0, 1.0).acos().to_degrees();
        assert!(ang(&out[k], &clean[k]) < 5.0, "{}", ang(&out[k], &clean[k]));
        // Faces touching the crease keep their side's normal within a few degrees.
        let worst = (0..m.faces.len())
            .filter(|&f| f != k)
            .map(|f| ang(&out[f], &clean[f]))
            .fold(0.0, f64::max);
        assert!(worst < 6.0, "{worst}");
    }
}
