//! A pinhole look-at camera: `eye` looks at `target` with +Z as the up hint (the project's
//! convention: +Z is up), a vertical field of view and a W×H image, row 0 at the top.

use glam::DVec3;

/// Errors of building a camera.
#[derive(Debug, thiserror::Error)]
pub enum CameraError {
    /// Eye and target coincide.
    #[error("the eye and the target coincide: no view direction")]
    Degenerate,
    /// The field of view is not in (0, 180).
    #[error("field of view {0} degrees must be in (0, 180)")]
    Fov(f64),
}

/// A look-at pinhole camera.
#[derive(Clone, Copy, Debug)]
pub struct Camera {
    /// Position of the eye.
    pub eye: DVec3,
    forward: DVec3,
    right: DVec3,
    up: DVec3,
    tan_half: f64,
    /// Image width in pixels.
    pub width: usize,
    /// Image height in pixels.
    pub height: usize,
}

impl Camera {
    /// A camera at `eye` looking at `target`, vertical field of view `fov_deg`, `width`×`height`.
    pub fn look_at(eye: DVec3, target: DVec3, fov_deg: f64, width: usize, height: usize) -> Result<Self, CameraError> {
        if !(fov_deg > 0.0 && fov_deg < 180.0) {
            return Err(CameraError::Fov(fov_deg));
        }
        let forward = (target - eye).try_normalize().ok_or(CameraError::Degenerate)?;
        // Up hint +Z, or +Y when looking straight along Z.
        let hint = if forward.cross(DVec3::Z).length() < 1e-6 { DVec3::Y } else { DVec3::Z };
        let right = forward.cross(hint).normalize();
        let up = right.cross(forward);
        Ok(Camera { eye, forward, right, up, tan_half: (fov_deg.to_radians() / 2.0).tan(), width, height })
    }

    /// Unit direction of the ray through the centre of pixel (x, y).
    pub fn ray(&self, x: usize, y: usize) -> DVec3 {
        let aspect = self.width as f64 / self.height as f64;
        let sx = (2.0 * (x as f64 + 0.5) / self.width as f64 - 1.0) * self.tan_half * aspect;
        let sy = (1.0 - 2.0 * (y as f64 + 0.5) / self.height as f64) * self.tan_half;
        (self.forward + sx * self.right + sy * self.up).normalize()
    }

    /// Unit direction from the scene towards the eye along the optical axis: the single view
    /// direction of a distant viewer (R&H 2002 eq. 12).
    pub fn view_direction(&self) -> DVec3 {
        -self.forward
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn centre_ray_points_at_the_target_and_corners_span_the_fov() {
        let cam = Camera::look_at(DVec3::new(0.0, -4.0, 0.0), DVec3::ZERO, 90.0, 2, 2).unwrap();
        // 2×2 pixels: centres at ±½ of the half-extent tan 45° = 1.
        let d = cam.ray(1, 0);
        let expect = DVec3::new(0.5, 1.0, 0.5).normalize();
        assert!((d - expect).length() < 1e-12, "{d:?}");
        assert!((cam.view_direction() - DVec3::new(0.0, -1.0, 0.0)).length() < 1e-12);
        assert!(Camera::look_at(DVec3::ZERO, DVec3::ZERO, 40.0, 2, 2).is_err());
    }
}
