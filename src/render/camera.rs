//! Orthographic cameras for the four standard views, fitted to the object.
//!
//! A camera is an orthonormal frame (right `r`, up `u`, toward the viewer `b`) and a scale `s`
//! in pixels per model unit. A point `p` maps to the screen (x to the right, y down) as
//! `x = cx + s (r.(p - c))`, `y = cy - s (u.(p - c))`, and to the depth `d = -b.(p - c)`
//! (growing away from the viewer), where `c` is the centre of the object's projected box.
//! The scale makes the larger of the projected box's two sides fill `fill` (e.g. 0.9) of the
//! frame's matching side.

use crate::error::{Error, Result};
use nalgebra::{Point3, Vector3};
use std::str::FromStr;

/// The standard views.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum View {
    /// From the front-right-top octant, direction (1, 1, 1) in the up-axis frame.
    #[default]
    Iso,
    /// Looking against the front axis (+Z when Y is up, -Y when Z is up).
    Front,
    /// Looking down the up axis, front at the bottom of the picture.
    Top,
    /// From the right (+X), looking toward -X.
    Side,
    /// Looking up the up axis from below, front at the top of the picture (the base of a
    /// scanned part, where its holes usually are).
    Bottom,
    /// From behind, looking toward the front axis.
    Back,
}

impl FromStr for View {
    type Err = Error;
    fn from_str(s: &str) -> Result<View> {
        match s.to_ascii_lowercase().as_str() {
            "iso" | "isometric" => Ok(View::Iso),
            "front" => Ok(View::Front),
            "top" => Ok(View::Top),
            "side" | "right" => Ok(View::Side),
            "bottom" => Ok(View::Bottom),
            "back" => Ok(View::Back),
            other => Err(Error::InvalidOption(format!(
                "unknown view '{other}'; expected iso, front, top, side, bottom or back"
            ))),
        }
    }
}

/// Which model axis points up in the picture.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum UpAxis {
    /// +Y up (most scan and graphics meshes: OBJ, PLY).
    #[default]
    Y,
    /// +Z up (CAD convention).
    Z,
}

impl FromStr for UpAxis {
    type Err = Error;
    fn from_str(s: &str) -> Result<UpAxis> {
        match s.to_ascii_lowercase().as_str() {
            "y" | "+y" => Ok(UpAxis::Y),
            "z" | "+z" => Ok(UpAxis::Z),
            other => Err(Error::InvalidOption(format!(
                "unknown up axis '{other}'; expected y or z"
            ))),
        }
    }
}

/// A fitted orthographic camera.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    /// Screen right, in model coordinates.
    pub right: Vector3<f64>,
    /// Screen up, in model coordinates.
    pub up: Vector3<f64>,
    /// Toward the viewer, in model coordinates (`right x up`).
    pub back: Vector3<f64>,
    /// Model point at the screen position (`cx`, `cy`).
    pub center: Point3<f64>,
    /// Pixels per model unit.
    pub scale: f64,
    pub cx: f64,
    pub cy: f64,
}

impl Camera {
    /// The frame of a view: (right, up, back).
    pub fn frame(view: View, up_axis: UpAxis) -> (Vector3<f64>, Vector3<f64>, Vector3<f64>) {
        // Work in a Y-up frame; for Z-up models map Y-up directions d to model directions by
        // (x, y, z) -> (x, -z, y), which sends the Y-up "front" (+Z) to -Y and "up" to +Z.
        let to_model = |v: Vector3<f64>| match up_axis {
            UpAxis::Y => v,
            UpAxis::Z => Vector3::new(v.x, -v.z, v.y),
        };
        let (back, up_hint) = match view {
            View::Front => (Vector3::z(), Vector3::y()),
            View::Side => (Vector3::x(), Vector3::y()),
            View::Top => (Vector3::y(), -Vector3::z()),
            View::Bottom => (-Vector3::y(), Vector3::z()),
            View::Back => (-Vector3::z(), Vector3::y()),
            View::Iso => (Vector3::new(1.0, 1.0, 1.0).normalize(), Vector3::y()),
        };
        let (back, up_hint) = (to_model(back), to_model(up_hint));
        let right = up_hint.cross(&back).normalize();
        let up = back.cross(&right);
        (right, up, back)
    }

    /// Fits a camera so the points fill `fill` of the `width` x `height` area whose top-left
    /// corner is at (`x0`, 0). Errors when there are no points or a coordinate is not finite.
    pub fn fit<'a>(
        view: View,
        up_axis: UpAxis,
        points: impl Iterator<Item = &'a Point3<f64>>,
        x0: f64,
        width: f64,
        height: f64,
        fill: f64,
    ) -> Result<Camera> {
        let (right, up, back) = Camera::frame(view, up_axis);
        let (mut umin, mut umax, mut vmin, mut vmax) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
        let mut any = false;
        for p in points {
            if !p.iter().all(|c| c.is_finite()) {
                return Err(Error::Degenerate(format!(
                    "cannot render a non-finite point ({}, {}, {})",
                    p.x, p.y, p.z
                )));
            }
            let (u, v) = (p.coords.dot(&right), p.coords.dot(&up));
            umin = umin.min(u);
            umax = umax.max(u);
            vmin = vmin.min(v);
            vmax = vmax.max(v);
            any = true;
        }
        if !any {
            return Err(Error::Degenerate("nothing to render: no points".into()));
        }
        let (du, dv) = (umax - umin, vmax - vmin);
        let su = if du > 0.0 { width / du } else { f64::INFINITY };
        let sv = if dv > 0.0 { height / dv } else { f64::INFINITY };
        let mut scale = fill * su.min(sv);
        if !scale.is_finite() || scale <= 0.0 {
            // A single point (or all coincide): any scale shows it.
            scale = 1.0;
        }
        let (uc, vc) = (0.5 * (umin + umax), 0.5 * (vmin + vmax));
        Ok(Camera {
            right,
            up,
            back,
            center: Point3::from(right * uc + up * vc),
            scale,
            cx: x0 + 0.5 * width,
            cy: 0.5 * height,
        })
    }

    /// Screen position (pixels, y down) and depth (model units, away from the viewer).
    #[inline]
    pub fn project(&self, p: &Point3<f64>) -> [f64; 3] {
        let d = p - self.center;
        [
            self.cx + self.scale * d.dot(&self.right),
            self.cy - self.scale * d.dot(&self.up),
            -d.dot(&self.back),
        ]
    }

    /// A model-space direction in the camera frame (x right, y up, z toward the viewer).
    #[inline]
    pub fn to_camera(&self, v: &Vector3<f64>) -> Vector3<f64> {
        Vector3::new(v.dot(&self.right), v.dot(&self.up), v.dot(&self.back))
    }

    /// The same camera for a picture `factor` times larger (supersampling).
    pub fn scaled(&self, factor: f64) -> Camera {
        Camera {
            scale: self.scale * factor,
            cx: self.cx * factor,
            cy: self.cy * factor,
            ..*self
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_are_right_handed_and_views_look_where_named() {
        for up in [UpAxis::Y, UpAxis::Z] {
            for v in [
                View::Iso,
                View::Front,
                View::Top,
                View::Side,
                View::Bottom,
                View::Back,
            ] {
                let (r, u, b) = Camera::frame(v, up);
                assert!((r.cross(&u) - b).norm() < 1e-12, "{v:?} {up:?}");
                assert!((r.norm() - 1.0).abs() < 1e-12 && r.dot(&u).abs() < 1e-12);
            }
        }
        // Y up: front looks from +Z with +Y up; top from +Y.
        let (_, u, b) = Camera::frame(View::Front, UpAxis::Y);
        assert_eq!((u, b), (Vector3::y(), Vector3::z()));
        assert_eq!(Camera::frame(View::Top, UpAxis::Y).2, Vector3::y());
        // Z up: front looks from -Y with +Z up; top from +Z; side from +X.
        let (_, u, b) = Camera::frame(View::Front, UpAxis::Z);
        assert!((u - Vector3::z()).norm() < 1e-12 && (b + Vector3::y()).norm() < 1e-12);
        assert!((Camera::frame(View::Top, UpAxis::Z).2 - Vector3::z()).norm() < 1e-12);
        assert!((Camera::frame(View::Side, UpAxis::Z).2 - Vector3::x()).norm() < 1e-12);
    }

    #[test]
    fn fit_fills_the_frame() {
        let pts = [Point3::new(-1.0, -0.5, 0.0), Point3::new(3.0, 1.5, 2.0)];
        let c = Camera::fit(View::Front, UpAxis::Y, pts.iter(), 0.0, 400.0, 300.0, 0.9).unwrap();
        let a = c.project(&pts[0]);
        let b = c.project(&pts[1]);
        // Width 4 and height 2 units: width limits, 360 px wide, centred.
        assert!(((b[0] - a[0]) - 360.0).abs() < 1e-9);
        assert!(((a[0] + b[0]) / 2.0 - 200.0).abs() < 1e-9);
        assert!(((a[1] + b[1]) / 2.0 - 150.0).abs() < 1e-9);
        assert!(a[1] > b[1], "y grows downward");
        assert!(
            a[2] > b[2],
            "the point at larger z is nearer in the front view"
        );
        assert!(Camera::fit(View::Iso, UpAxis::Y, [].iter(), 0.0, 4.0, 4.0, 0.9).is_err());
        let one = [Point3::new(1.0, 2.0, 3.0)];
        let c = Camera::fit(View::Iso, UpAxis::Y, one.iter(), 0.0, 4.0, 4.0, 0.9).unwrap();
        assert!((c.project(&one[0])[0] - 2.0).abs() < 1e-9);
    }

    #[test]
    fn parse_names() {
        assert_eq!("ISO".parse::<View>().unwrap(), View::Iso);
        assert_eq!("side".parse::<View>().unwrap(), View::Side);
        assert_eq!("Bottom".parse::<View>().unwrap(), View::Bottom);
        assert_eq!("back".parse::<View>().unwrap(), View::Back);
        assert!("diagonal".parse::<View>().is_err());
        assert_eq!("z".parse::<UpAxis>().unwrap(), UpAxis::Z);
    }
}
