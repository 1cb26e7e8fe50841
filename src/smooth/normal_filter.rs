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

/// `passes` bilateral passes over the unit face normals `normals` (zero for degenerate faces,
/// which neither receive nor give), weighted by `areas`; the result in `out`.
pub(crate) fn filter_normals(
    faces: &[[u32; 3]],
    adj: &Adjacency,
    areas: &[f64],
    normals: &[Vector3<f64>],
    sigma: f64,
    passes: usize,
    out: &mut Vec<Vector3<f64>>,
) {
    out.clear();
    out.extend_from_slice(normals);
    if passes == 0 || sigma.is_nan() || sigma <= 0.0 {
        return;
    }
    let inv_s2 = 1.0 / (sigma * sigma);
    let mut tmp: Vec<Vector3<f64>> = Vec::with_capacity(normals.len());
    for _ in 0..passes {
        let cur: &[Vector3<f64>] = out;
        (0..cur.len())
            .into_par_iter()
            .map(|f| {
                let nf = cur[f];
                if nf.norm_squared() == 0.0 {
                    return nf;
                }
                let mut s = Vector3::zeros();
                for &v in &faces[f] {
                    for &g in adj.faces_of_vertex(v as usize) {
                        let ng = cur[g as usize];
                        let d2 = (nf - ng).norm_squared();
                        s += ng * (areas[g as usize] / (1.0 + d2 * inv_s2));
                    }
                }
                let l = s.norm();
                if l > 0.0 && l.is_finite() {
                    s / l
                } else {
                    nf
                }
            })
            .collect_into_vec(&mut tmp);
        std::mem::swap(out, &mut tmp);
    }
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
