//! Keeping a subset of a mesh's faces, with the vertices they use (renumbered in order).

use super::Mesh;

/// The faces with `keep[f]` true and the vertices they reference (normals kept for those).
pub fn retain_faces(mesh: &Mesh, keep: &[bool]) -> Mesh {
    let mut map = vec![u32::MAX; mesh.positions.len()];
    let mut out = Mesh::default();
    let mut normals = mesh.normals.as_ref().map(|_| Vec::new());
    for (f, k) in mesh.faces.iter().zip(keep) {
        if !*k {
            continue;
        }
        let mut t = [0u32; 3];
        for (j, &v) in f.iter().enumerate() {
            if map[v as usize] == u32::MAX {
                map[v as usize] = out.positions.len() as u32;
                out.positions.push(mesh.positions[v as usize]);
                if let (Some(dst), Some(src)) = (normals.as_mut(), mesh.normals.as_ref()) {
                    dst.push(src[v as usize]);
                }
            }
            t[j] = map[v as usize];
        }
        out.faces.push(t);
    }
    out.normals = normals;
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Point3;

    #[test]
    fn keeps_selected_faces_and_their_vertices() {
        let m = Mesh {
            positions: (0..5).map(|i| Point3::new(i as f64, 0.0, 0.0)).collect(),
            normals: None,
            faces: vec![[0, 1, 2], [2, 3, 4]],
        };
        let r = retain_faces(&m, &[false, true]);
        assert_eq!(r.faces, vec![[0, 1, 2]]);
        assert_eq!(r.positions[0].x, 2.0);
        assert_eq!(r.positions.len(), 3);
    }
}
