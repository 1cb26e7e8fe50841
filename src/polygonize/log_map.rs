//! Discrete log map at a net node: where a neighbouring node lands when the surface around the
//! node is unrolled onto its tangent plane. The net is relaxed in these unrolled
//! neighbourhoods ([`super::net_smooth`]), and its corners judged by their angles there
//! ([`unrolled_angle`], in the tests): the angles the patches will see (their corner tangents
//! lie in the node's tangent plane), not the angles of the chords in space.
//!
//! **Why.** Seed 004's patches take their corner tangents from the implicit's tangent plane at
//! the net node. Where the net wraps a crease rounded below the patch size (the rim of the
//! Stanford bunny's flat base), two chords that leave a node 50 degrees apart in space can
//! both climb the far side of the crease and reach it in nearly the same tangent direction:
//! the patch between them is a sliver at that corner (measured: 9 degrees on the bunny at
//! 1,500 patches), its iso-curves nearly parallel there, and OpenCASCADE's point projection
//! falls into a local minimum on it. Chord angles in space do not see this; angles in the
//! unrolled neighbourhood do.
//!
//! **The map.** For node p with unit normal n_p and neighbour q with unit normal n_q, take the
//! surface between them as a circular arc in the plane of its end normals (a normal section of
//! constant curvature): the normals turn by theta = angle(n_q, n_p), the chord d = q - p makes
//! the angle theta / 2 with the tangents at both ends, and the rotation by theta / 2 about the
//! axis n_q x n_p takes d to the tangent direction at p. Its length there is the arc length
//! |d| (theta / 2) / sin(theta / 2). So
//!
//!   log_p(q) = |d| (theta / 2) / sin(theta / 2) * P_p(R(n_q x n_p, theta / 2) d) / |P_p(...)|,
//!
//! with P_p = I - n_p n_p^T removing what the arc assumption leaves out of the tangent plane.
//! For theta -> 0 this is the chord projected onto the tangent plane, with the chord's length;
//! for a chord that leaves p along its normal (climbing a crease), the half rotation turns it
//! into the direction toward the crease that the surface actually takes, where a plain
//! projection would take the direction from the chord's small tangential part.
//!
//! Normals turned by more than [`MAX_TURN_DEG`] (a net edge wrapping the rim of a plate
//! thinner than a voxel, whose end normals are nearly opposed) leave the rotation axis
//! undefined; there the map falls back to the projected chord.

use nalgebra::{Point3, Rotation3, Unit, Vector3};

/// Largest turning of the normals for which the half rotation is used, degrees.
pub const MAX_TURN_DEG: f64 = 150.0;

/// The unrolled position of `q` (unit normal `nq`) seen from `p` (unit normal `np`), as a
/// vector in p's tangent plane (module doc). `None` when q coincides with p or lies on p's
/// normal line with no turning to tell a direction.
pub fn log_map(
    p: &Point3<f64>,
    np: &Vector3<f64>,
    q: &Point3<f64>,
    nq: &Vector3<f64>,
) -> Option<Vector3<f64>> {
    let d = q - p;
    let len = d.norm();
    if !(len > 0.0 && len.is_finite()) {
        return None;
    }
    let axis = nq.cross(np);
    let theta = axis.norm().atan2(nq.dot(np));
    let (dir, arc) = match Unit::try_new(axis, 1e-12) {
        Some(a) if theta.to_degrees() <= MAX_TURN_DEG => {
            let half = 0.5 * theta;
            (
                Rotation3::from_axis_angle(&a, half) * d,
                len * half / half.sin(),
            )
        }
        _ => (d, len),
    };
    let t = dir - np * np.dot(&dir);
    let tn = t.norm();
    (tn > 1e-9 * len && tn.is_finite()).then(|| t * (arc / tn))
}

/// The angle, in degrees, at node `p` between its neighbours `a` and `b` in the unrolled
/// neighbourhood ([`log_map`]); `None` when either direction is undefined.
pub fn unrolled_angle(
    p: (&Point3<f64>, &Vector3<f64>),
    a: (&Point3<f64>, &Vector3<f64>),
    b: (&Point3<f64>, &Vector3<f64>),
) -> Option<f64> {
    let ta = log_map(p.0, p.1, a.0, a.1)?;
    let tb = log_map(p.0, p.1, b.0, b.1)?;
    Some(ta.angle(&tb).to_degrees())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// On a cylinder the map is exact along a normal section: a point a quarter turn round
    /// the circle lands at its arc length, straight along the circle's tangent.
    #[test]
    fn normal_section_of_a_cylinder_is_unrolled_exactly() {
        let r = 2.0;
        let p = Point3::new(r, 0.0, 0.0);
        let np = Vector3::x();
        for deg in [1.0f64, 30.0, 90.0, 140.0] {
            let th = deg.to_radians();
            let q = Point3::new(r * th.cos(), r * th.sin(), 0.0);
            let nq = Vector3::new(th.cos(), th.sin(), 0.0);
            let t = log_map(&p, &np, &q, &nq).unwrap();
            assert!((t - Vector3::y() * (r * th)).norm() < 1e-12, "{deg}: {t}");
        }
    }

    /// Along a cylinder's ruling the map is the chord; a helix-like neighbour (half a turn
    /// round, some way along the axis) unrolls to its developed position within the
    /// arc assumption's error.
    #[test]
    fn cylinder_develops_onto_the_plane() {
        let r = 1.0;
        let p = Point3::new(r, 0.0, 0.0);
        let np = Vector3::x();
        let q = Point3::new(r, 0.0, 0.7);
        let t = log_map(&p, &np, &q, &np).unwrap();
        assert!((t - Vector3::new(0.0, 0.0, 0.7)).norm() < 1e-12);
        let th = 0.6f64;
        let q = Point3::new(r * th.cos(), r * th.sin(), 0.3);
        let nq = Vector3::new(th.cos(), th.sin(), 0.0);
        let t = log_map(&p, &np, &q, &nq).unwrap();
        let developed = Vector3::new(0.0, r * th, 0.3);
        let err = t.angle(&developed).to_degrees();
        assert!(err < 2.0, "direction off by {err} degrees");
        assert!((t.norm() - developed.norm()).abs() < 0.02 * developed.norm());
    }

    /// A chord climbing a rounded crease almost along the node's normal: projected, its
    /// direction comes from its small sideways part; unrolled, it points at the crease.
    #[test]
    fn chord_over_a_crease_points_at_the_crease() {
        // Base plane y = 0 seen from below (normal -y), wall z = 0.01 facing +z, node on the
        // base 1e-3 from the rim; the neighbour 8e-3 up the wall and 2e-3 along the rim.
        let p = Point3::new(0.0, 0.0, 0.009);
        let np = -Vector3::y();
        let q = Point3::new(-0.002, 0.008, 0.01);
        let nq = Vector3::z();
        let t = log_map(&p, &np, &q, &nq).unwrap();
        let developed = Vector3::new(-0.002, 0.0, 0.009);
        assert!(t.angle(&developed).to_degrees() < 6.0, "{t}");
        let projected = (q - p) - np * np.dot(&(q - p));
        assert!(projected.angle(&developed).to_degrees() > 30.0);
    }

    #[test]
    fn opposed_normals_fall_back_to_the_projected_chord() {
        let p = Point3::origin();
        let q = Point3::new(0.3, 0.4, 0.0);
        let t = log_map(&p, &Vector3::z(), &q, &-Vector3::z()).unwrap();
        assert!((t - Vector3::new(0.3, 0.4, 0.0)).norm() < 1e-12);
        assert!(log_map(
            &p,
            &Vector3::z(),
            &Point3::new(0.0, 0.0, 1.0),
            &Vector3::z()
        )
        .is_none());
        assert!(log_map(&p, &Vector3::z(), &p, &Vector3::z()).is_none());
    }
}
