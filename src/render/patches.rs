//! Pictures of B-spline patch models (a STEP file read back, or a fitted [`PatchNetwork`]):
//! every face tessellated on a grid of its parameter rectangle with the surface's own unit
//! normals `S_u × S_v / |S_u × S_v|` (flipped where the face's sense is reversed), shaded, and
//! the boundary of each face's parameter domain drawn on top as a dark closed polyline, so the
//! patch network is visible. Sides no other face shares (the boundary of an open shell, what
//! `fit --close open` leaves where the data stop) are drawn over them in [`OPEN_EDGE_COLOUR`].
//!
//! The grid density adapts to the face count: about [`TARGET_TRIANGLES`] triangles in all,
//! between 4 and 32 intervals per side of a face.

use super::{render_mesh_layers, ColorScale, Image, LineLayer, RenderOptions};
use crate::error::{Error, Result};
use crate::mesh::Mesh;
use crate::nurbs::{BSplineSurface, PatchNetwork};
use nalgebra::{Point3, Vector3};
use rayon::prelude::*;

/// Colour of the open boundary (face sides shared by no other face).
pub const OPEN_EDGE_COLOUR: [u8; 3] = [235, 120, 20];

/// The sides of the face outlines of [`tessellate_faces`] (each `4 n + 1` points, side k the
/// points `k n ..= (k + 1) n`) that no other side matches: both ends and the mean point
/// within 1e-6 of the model's size of another side's (in either direction). Shared sides of a
/// sewn network evaluate the same curve on both faces, so they match far closer than that.
pub fn open_sides(outlines: &[Vec<Point3<f64>>]) -> Vec<Vec<Point3<f64>>> {
    let sides: Vec<&[Point3<f64>]> = outlines
        .iter()
        .filter(|o| o.len() >= 5 && (o.len() - 1) % 4 == 0)
        .flat_map(|o| {
            let n = (o.len() - 1) / 4;
            (0..4).map(move |k| &o[k * n..=(k + 1) * n])
        })
        .collect();
    // The mean of a side's points: the same whichever way the side is walked.
    let mids: Vec<Point3<f64>> = sides
        .iter()
        .map(|s| Point3::from(s.iter().map(|p| p.coords).sum::<Vector3<f64>>() / s.len() as f64))
        .collect();
    let Some(bb) = crate::mesh::Aabb::of(&mids) else {
        return Vec::new();
    };
    let tol = 1e-6 * bb.diagonal().max(f64::MIN_POSITIVE);
    let Ok(tree) = crate::spatial::KdTree::build(&mids) else {
        return Vec::new();
    };
    let close = |a: &Point3<f64>, b: &Point3<f64>| (a - b).norm() <= tol;
    (0..sides.len())
        .into_par_iter()
        .filter(|&i| {
            let s = sides[i];
            let (a, b) = (s[0], s[s.len() - 1]);
            !tree.within(&mids[i], tol).into_iter().any(|j| {
                let o = sides[j];
                let (c, d) = (o[0], o[o.len() - 1]);
                j != i && ((close(&a, &c) && close(&b, &d)) || (close(&a, &d) && close(&b, &c)))
            })
        })
        .map(|i| sides[i].to_vec())
        .collect()
}

/// The patch boundaries in the options' line colour and the open boundary over them.
pub fn outline_layers<'a>(
    lines: &'a [Vec<Point3<f64>>],
    open: &'a [Vec<Point3<f64>>],
    opts: &RenderOptions,
) -> [LineLayer<'a>; 2] {
    [
        LineLayer {
            lines,
            color: opts.line_color,
            width: opts.line_width,
        },
        LineLayer {
            lines: open,
            color: OPEN_EDGE_COLOUR,
            width: 2.5 * opts.line_width,
        },
    ]
}

/// Triangle budget of a whole picture's tessellation.
pub const TARGET_TRIANGLES: usize = 600_000;

/// Intervals per side of a face for `faces` faces: `sqrt(TARGET / (2 faces))`, in 4..=32.
pub fn resolution(faces: usize) -> usize {
    let n = (TARGET_TRIANGLES as f64 / (2.0 * faces.max(1) as f64)).sqrt();
    (n.round() as usize).clamp(4, 32)
}

/// One face to draw: its surface and whether `S_u × S_v` is its outward (front) normal.
#[derive(Debug, Clone, Copy)]
pub struct FaceRef<'a> {
    pub surface: &'a BSplineSurface,
    pub same_sense: bool,
}

/// One face's grid points, their normals and its outline.
type FaceTiles = (Vec<Point3<f64>>, Vec<Vector3<f64>>, Vec<Point3<f64>>);

/// Triangles of every face on an `n` x `n` grid of its parameter rectangle (vertices not
/// shared between faces), with surface normals, and each face's parameter-domain boundary as
/// one closed polyline of `4 n` segments. Faces are processed in parallel and concatenated in
/// input order (deterministic).
pub fn tessellate_faces(faces: &[FaceRef], n: usize) -> (Mesh, Vec<Vec<Point3<f64>>>) {
    let n = n.max(1);
    let parts: Vec<FaceTiles> = faces
        .par_iter()
        .map(|f| {
            let s = f.surface;
            let (u0, u1) = s.domain_u();
            let (v0, v1) = s.domain_v();
            let (uc, vc) = (0.5 * (u0 + u1), 0.5 * (v0 + v1));
            let at = |i: usize, j: usize| {
                (
                    u0 + (u1 - u0) * i as f64 / n as f64,
                    v0 + (v1 - v0) * j as f64 / n as f64,
                )
            };
            let mut pos = Vec::with_capacity((n + 1) * (n + 1));
            let mut nrm = Vec::with_capacity((n + 1) * (n + 1));
            for i in 0..=n {
                for j in 0..=n {
                    let (u, v) = at(i, j);
                    pos.push(s.evaluate(u, v));
                    // At a collapsed corner or edge the normal is undefined: take it a little
                    // way toward the face centre.
                    let normal = [0.0, 1e-3, 1e-2, 1e-1]
                        .iter()
                        .find_map(|&t| s.normal(u + t * (uc - u), v + t * (vc - v)))
                        .unwrap_or_else(Vector3::zeros);
                    nrm.push(if f.same_sense { normal } else { -normal });
                }
            }
            let mut outline = Vec::with_capacity(4 * n + 1);
            for k in 0..n {
                outline.push(s.evaluate(at(k, 0).0, v0));
            }
            for k in 0..n {
                outline.push(s.evaluate(u1, at(0, k).1));
            }
            for k in (1..=n).rev() {
                outline.push(s.evaluate(at(k, 0).0, v1));
            }
            for k in (1..=n).rev() {
                outline.push(s.evaluate(u0, at(0, k).1));
            }
            outline.push(outline[0]);
            (pos, nrm, outline)
        })
        .collect();
    let mut mesh = Mesh::default();
    let mut normals = Vec::with_capacity(faces.len() * (n + 1) * (n + 1));
    let mut lines = Vec::with_capacity(faces.len());
    for ((pos, nrm, outline), f) in parts.into_iter().zip(faces) {
        let base = mesh.positions.len() as u32;
        let id = |i: usize, j: usize| base + (i * (n + 1) + j) as u32;
        for i in 0..n {
            for j in 0..n {
                let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
                if f.same_sense {
                    mesh.faces.push([a, b, c]);
                    mesh.faces.push([a, c, d]);
                } else {
                    mesh.faces.push([a, c, b]);
                    mesh.faces.push([a, d, c]);
                }
            }
        }
        mesh.positions.extend(pos);
        normals.extend(nrm);
        lines.push(outline);
    }
    // The renderer uses the normals only when all are usable; otherwise it averages face
    // normals itself.
    mesh.normals = Some(normals);
    (mesh, lines)
}

/// Renders faces shaded grey with their patch boundaries as dark lines and the open boundary
/// in [`OPEN_EDGE_COLOUR`].
pub fn render_faces(faces: &[FaceRef], opts: &RenderOptions) -> Result<Image> {
    if faces.is_empty() {
        return Err(Error::Degenerate("nothing to render: no faces".into()));
    }
    let (mesh, lines) = tessellate_faces(faces, resolution(faces.len()));
    let open = open_sides(&lines);
    render_mesh_layers(&mesh, None, &outline_layers(&lines, &open, opts), opts)
}

/// The faces of a network, for [`render_faces`].
pub fn network_faces(net: &PatchNetwork) -> Vec<FaceRef<'_>> {
    net.faces
        .iter()
        .map(|f| FaceRef {
            surface: &f.surface,
            same_sense: f.same_sense,
        })
        .collect()
}

/// The picture `scansurf fit --preview` writes: the fitted network with its patch boundaries,
/// coloured by the deviation of the input points when `deviation` gives one distance per
/// point of `points` (each surface vertex takes the inverse-distance weighted deviation of its
/// nearest input points; the scale runs from 0 to the 99th percentile so a few outliers do
/// not wash it out), else shaded grey.
pub fn network_preview(
    net: &PatchNetwork,
    points: &[Point3<f64>],
    deviation: Option<&[f64]>,
    opts: &RenderOptions,
) -> Result<Image> {
    let faces = network_faces(net);
    if faces.is_empty() {
        return Err(Error::Degenerate("nothing to render: no patches".into()));
    }
    let (mesh, lines) = tessellate_faces(&faces, resolution(faces.len()));
    let open = open_sides(&lines);
    let layers = outline_layers(&lines, &open, opts);
    let dev = deviation.filter(|d| d.len() == points.len() && !points.is_empty());
    let Some(dev) = dev else {
        return render_mesh_layers(&mesh, None, &layers, opts);
    };
    let Some((scalars, scale)) = point_deviation_colours(&mesh.positions, points, dev)? else {
        return render_mesh_layers(&mesh, None, &layers, opts);
    };
    let mut o = opts.clone();
    o.legend_title = "point deviation".into();
    render_mesh_layers(&mesh, Some((&scalars, scale)), &layers, &o)
}

/// Per-vertex scalars and their colour scale for a surface coloured by the deviation of nearby
/// input points: each vertex of `surface` takes the inverse-distance weighted mean of
/// `deviation` over its nearest `points` ([`interpolated_values`]); the scale runs from 0 to
/// the 99th percentile of the finite deviations, so a few outliers do not wash it out. `None`
/// when no deviation is finite.
pub fn point_deviation_colours(
    surface: &[Point3<f64>],
    points: &[Point3<f64>],
    deviation: &[f64],
) -> Result<Option<(Vec<f64>, ColorScale)>> {
    if points.is_empty() || deviation.len() != points.len() {
        return Err(Error::Degenerate(format!(
            "{} deviation values for {} points",
            deviation.len(),
            points.len()
        )));
    }
    let mut finite: Vec<f64> = deviation
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .collect();
    if finite.is_empty() {
        return Ok(None);
    }
    finite.sort_unstable_by(f64::total_cmp);
    let p99 = finite[((finite.len() - 1) as f64 * 0.99).round() as usize];
    let scale = if p99 > 0.0 {
        ColorScale::sequential(0.0, p99)?
    } else {
        ColorScale::auto(&finite)?
    };
    Ok(Some((
        interpolated_values(surface, points, deviation)?,
        scale,
    )))
}

/// Neighbours whose values [`interpolated_values`] blends.
const BLEND: usize = 8;

/// For every query point, the inverse-distance weighted mean (weights 1 / d^2) of the finite
/// `values` of its [`BLEND`] nearest `points` (k-d tree); a query on a point takes its value.
/// On a sparse cloud (a few thousand mesh vertices) the nearest value alone paints each
/// patch in Voronoi cells of the points; the blend shades smoothly between them.
fn interpolated_values(
    queries: &[Point3<f64>],
    points: &[Point3<f64>],
    values: &[f64],
) -> Result<Vec<f64>> {
    let tree = crate::spatial::KdTree::build(points)?;
    Ok(queries
        .par_iter()
        .map(|q| {
            let near = tree.knn(q, BLEND);
            let (mut sum, mut wsum) = (0.0, 0.0);
            for &(k, d) in &near {
                let v = values[k];
                if !v.is_finite() {
                    continue;
                }
                if d <= 0.0 {
                    return v;
                }
                let w = 1.0 / (d * d);
                sum += w * v;
                wsum += w;
            }
            if wsum > 0.0 && (sum / wsum).is_finite() {
                sum / wsum
            } else {
                near.first().map_or(f64::NAN, |&(k, _)| values[k])
            }
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::nurbs::Params;

    /// The blend reproduces the values at the points, is the plain mean halfway between two
    /// equal-distance points, ignores non-finite values, and is smooth rather than a step.
    #[test]
    fn deviation_blend_interpolates() {
        let pts = [Point3::new(0.0, 0.0, 0.0), Point3::new(1.0, 0.0, 0.0)];
        let v = interpolated_values(&pts, &pts, &[0.0, 1.0]).unwrap();
        assert_eq!(v, vec![0.0, 1.0]);
        let q: Vec<Point3<f64>> = (0..=10)
            .map(|i| Point3::new(i as f64 / 10.0, 0.3, 0.0))
            .collect();
        let v = interpolated_values(&q, &pts, &[0.0, 1.0]).unwrap();
        assert!((v[5] - 0.5).abs() < 1e-12, "{v:?}");
        assert!(v.windows(2).all(|w| w[1] > w[0]), "{v:?}");
        assert!(v[4] > 0.3 && v[6] < 0.7, "a blend, not a step: {v:?}");
        let v = interpolated_values(&q, &pts, &[f64::NAN, 2.0]).unwrap();
        assert!(v.iter().all(|&x| x == 2.0), "{v:?}");
    }

    fn bump(x0: f64) -> BSplineSurface {
        let k = Params::uniform(3).unwrap().cubic_knots();
        let ctrl = (0..6)
            .map(|i| {
                (0..6)
                    .map(|j| {
                        let (x, y) = (x0 + i as f64 * 0.2, j as f64 * 0.2);
                        Point3::new(x, 0.3 * ((i * j) as f64 * 0.3).sin(), y)
                    })
                    .collect()
            })
            .collect();
        BSplineSurface::new(3, 3, k.clone(), k, ctrl).unwrap()
    }

    #[test]
    fn tessellation_counts_and_outlines() {
        let (a, b) = (bump(0.0), bump(1.0));
        let faces = [
            FaceRef {
                surface: &a,
                same_sense: true,
            },
            FaceRef {
                surface: &b,
                same_sense: false,
            },
        ];
        let (mesh, lines) = tessellate_faces(&faces, 5);
        assert_eq!(mesh.positions.len(), 2 * 36);
        assert_eq!(mesh.faces.len(), 2 * 50);
        assert_eq!(lines.len(), 2);
        assert_eq!(lines[0].len(), 21);
        assert_eq!(lines[0][0], lines[0][20]);
        // Two separate faces: all eight sides are open; a face with itself twice: none.
        assert_eq!(open_sides(&lines).len(), 8);
        let twice = vec![lines[0].clone(), lines[0].iter().rev().copied().collect()];
        assert!(open_sides(&twice).is_empty());
        // The outline passes the four corners.
        for (u, v) in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)] {
            let c = a.evaluate(u, v);
            assert!(lines[0].iter().any(|p| (p - c).norm() < 1e-12));
        }
        // Normals are unit and agree with the triangles' winding.
        let nm = mesh.normals.as_ref().unwrap();
        for (fi, f) in mesh.faces.iter().enumerate() {
            let cross = mesh.face_cross(fi);
            assert!(cross.dot(&nm[f[0] as usize]) > 0.0, "face {fi}");
            assert!((nm[f[0] as usize].norm() - 1.0).abs() < 1e-9);
        }
        assert_eq!(resolution(1), 32);
        assert_eq!(resolution(1500), 14);
        assert_eq!(resolution(1_000_000), 4);
    }

    #[test]
    fn picture_shows_lines_over_shading() {
        let (a, b) = (bump(0.0), bump(1.0));
        let faces = [
            FaceRef {
                surface: &a,
                same_sense: true,
            },
            FaceRef {
                surface: &b,
                same_sense: true,
            },
        ];
        let opts = RenderOptions {
            width: 300,
            height: 200,
            ..RenderOptions::default()
        };
        let img = render_faces(&faces, &opts).unwrap();
        let s = img.stats(opts.background);
        assert!(s.foreground_fraction > 0.2, "{s:?}");
        let pixels = || (0..img.height).flat_map(|y| (0..img.width).map(move |x| (x, y)));
        let dark = pixels()
            .filter(|&(x, y)| img.get(x, y).iter().all(|&c| c < 80))
            .count();
        // The outer sides are the open boundary, in orange; the shared side is dark.
        let orange = pixels()
            .filter(|&(x, y)| {
                let c = img.get(x, y);
                c[0] > 190 && (80..170).contains(&c[1]) && c[2] < 90
            })
            .count();
        assert!(
            dark > 30 && orange > 300,
            "{dark} dark, {orange} orange pixels"
        );
        assert!(render_faces(&[], &opts).is_err());
    }
}
