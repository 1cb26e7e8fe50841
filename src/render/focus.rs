//! `render --focus X,Y,Z,R`: draw only what lies within the ball of radius R around (X, Y, Z),
//! framed to fill the picture. Meant for looking at one spot of a result, e.g. the largest
//! normal jumps `fit --report` lists with their positions.
//!
//! A triangle is kept when all three of its vertices are inside the ball, a point of a cloud
//! when it is inside; boundary polylines are cut into the runs of consecutive points inside.

use crate::error::{Error, Result};
use crate::mesh::Mesh;
use nalgebra::Point3;
use std::str::FromStr;

/// A ball to crop a picture to.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Focus {
    pub center: Point3<f64>,
    pub radius: f64,
}

impl FromStr for Focus {
    type Err = Error;

    /// Parses `X,Y,Z,R` (four finite numbers, R > 0).
    fn from_str(s: &str) -> Result<Self> {
        let bad = || {
            Error::InvalidOption(format!(
                "--focus wants X,Y,Z,R (four numbers, radius > 0), got '{s}'"
            ))
        };
        let v: Vec<f64> = s
            .split(',')
            .map(|t| t.trim().parse::<f64>())
            .collect::<std::result::Result<_, _>>()
            .map_err(|_| bad())?;
        if v.len() != 4 || v.iter().any(|x| !x.is_finite()) || v[3] <= 0.0 {
            return Err(bad());
        }
        Ok(Focus {
            center: Point3::new(v[0], v[1], v[2]),
            radius: v[3],
        })
    }
}

impl Focus {
    fn contains(&self, p: &Point3<f64>) -> bool {
        (p - self.center).norm_squared() <= self.radius * self.radius
    }

    /// The part of `mesh` and `lines` inside the ball. A mesh keeps all its vertices (the
    /// renderer frames only the referenced ones); a cloud keeps the points inside. Errors when
    /// nothing is left.
    pub fn crop(
        &self,
        mut mesh: Mesh,
        lines: &[Vec<Point3<f64>>],
    ) -> Result<(Mesh, Vec<Vec<Point3<f64>>>)> {
        let is_cloud = mesh.faces.is_empty();
        if is_cloud {
            let keep: Vec<bool> = mesh.positions.iter().map(|p| self.contains(p)).collect();
            let mut k = keep.iter();
            mesh.positions.retain(|_| *k.next().unwrap_or(&false));
            if let Some(n) = mesh.normals.as_mut() {
                let mut k = keep.iter();
                n.retain(|_| *k.next().unwrap_or(&false));
            }
            if mesh.positions.is_empty() {
                return Err(self.nothing());
            }
        } else {
            let inside: Vec<bool> = mesh.positions.iter().map(|p| self.contains(p)).collect();
            mesh.faces
                .retain(|f| f.iter().all(|&v| inside.get(v as usize) == Some(&true)));
            if mesh.faces.is_empty() {
                return Err(self.nothing());
            }
        }
        Ok((mesh, self.crop_lines(lines)))
    }

    /// The runs of `lines` inside the ball (a line leaving and re-entering it gives two runs;
    /// runs of fewer than two points are dropped).
    pub fn crop_lines(&self, lines: &[Vec<Point3<f64>>]) -> Vec<Vec<Point3<f64>>> {
        let mut runs = Vec::new();
        for line in lines {
            let mut run: Vec<Point3<f64>> = Vec::new();
            for p in line {
                if self.contains(p) {
                    run.push(*p);
                } else if run.len() >= 2 {
                    runs.push(std::mem::take(&mut run));
                } else {
                    run.clear();
                }
            }
            if run.len() >= 2 {
                runs.push(run);
            }
        }
        runs
    }

    fn nothing(&self) -> Error {
        Error::InvalidOption(format!(
            "--focus {},{},{},{}: nothing of the model lies within that ball",
            self.center.x, self.center.y, self.center.z, self.radius
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_and_rejects() {
        let f: Focus = "1,2,3,0.5".parse().unwrap();
        assert_eq!(f.center, Point3::new(1.0, 2.0, 3.0));
        assert_eq!(f.radius, 0.5);
        for bad in [
            "1,2,3",
            "1,2,3,0",
            "1,2,3,-1",
            "a,b,c,d",
            "1,2,3,inf",
            "1,2,3,4,5",
        ] {
            assert!(bad.parse::<Focus>().is_err(), "{bad}");
        }
    }

    #[test]
    fn crops_faces_points_and_lines() {
        let mesh = Mesh {
            positions: vec![
                Point3::new(0.0, 0.0, 0.0),
                Point3::new(0.1, 0.0, 0.0),
                Point3::new(0.0, 0.1, 0.0),
                Point3::new(5.0, 0.0, 0.0),
            ],
            normals: None,
            faces: vec![[0, 1, 2], [1, 3, 2]],
        };
        let f = Focus {
            center: Point3::origin(),
            radius: 1.0,
        };
        let line = vec![
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(0.5, 0.0, 0.0),
            Point3::new(3.0, 0.0, 0.0),
            Point3::new(0.0, 0.5, 0.0),
        ];
        let (m, l) = f.crop(mesh.clone(), &[line]).unwrap();
        assert_eq!(m.faces, vec![[0, 1, 2]]);
        assert_eq!(l.len(), 1);
        assert_eq!(l[0].len(), 2);
        let cloud = Mesh {
            faces: vec![],
            ..mesh.clone()
        };
        let (c, _) = f.crop(cloud, &[]).unwrap();
        assert_eq!(c.positions.len(), 3);
        let far = Focus {
            center: Point3::new(100.0, 0.0, 0.0),
            radius: 1.0,
        };
        assert!(far.crop(mesh, &[]).is_err());
    }
}
