//! What changes from frame to frame, in the form an engine has it: the camera, its position,
//! the time and the lights. [`Frame::builtins`] turns it into the `SkyBuiltins` block.

use crate::builtins::{SkyBuiltins, SkyLight};
use glam::{Mat3, Mat4, Vec3, Vec4};

/// How the camera looks at the sky.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum View {
    /// A rotation from camera to world space (columns: right, up, back; the camera looks along
    /// −Z, Godot's and glam's convention) and the vertical field of view in radians. The aspect
    /// ratio is the target's.
    Rotation {
        /// Camera-to-world rotation (the inverse of the view matrix's rotation).
        camera_to_world: Mat3,
        /// Vertical field of view, radians.
        fov_y: f32,
    },
    /// Godot's camera as gdsky's scenes give it (yaw, pitch and vertical field of view in
    /// degrees, Euler YXZ), its basis and tan(fov/2) computed in f64 and rounded, exactly as
    /// `gdsky render` computes them; its position is not used ([`Frame::position`] is).
    Godot(skycore::Camera),
    /// The inverse of the view-projection matrix of a symmetric perspective camera, in any
    /// depth convention (standard or reversed Z, finite or infinite far plane): the rays are
    /// the directions from [`Frame::position`] through the unprojected pixels, from which the
    /// rotation and field of view are recovered.
    InverseViewProjection(Mat4),
}

impl View {
    /// The camera basis (right, up, back) and tan(vertical fov / 2) this view stands for,
    /// seen from `position`.
    pub fn basis(&self, position: Vec3) -> (Mat3, f32) {
        match *self {
            View::Rotation { camera_to_world, fov_y } => (camera_to_world, (0.5 * fov_y).tan()),
            View::Godot(camera) => {
                let b = camera.basis();
                let c = |v: glam::DVec3| Vec3::new(v.x as f32, v.y as f32, v.z as f32);
                (Mat3::from_cols(c(b.x_axis), c(b.y_axis), c(b.z_axis)), camera.tan_half_fov() as f32)
            }
            View::InverseViewProjection(inverse) => {
                // A point at NDC (x, y) and depth ½ lies on the ray through that pixel in either
                // depth convention; the ray's direction is from the camera's position to it.
                let ray = |x: f32, y: f32| {
                    let p = inverse * Vec4::new(x, y, 0.5, 1.0);
                    (p.truncate() / p.w - position).normalize_or_zero()
                };
                let forward = ray(0.0, 0.0);
                // Each ray scaled to unit distance along `forward`: forward + x·tan_x·right.
                let unit = |d: Vec3| d / d.dot(forward).max(f32::MIN_POSITIVE) - forward;
                let up_scaled = unit(ray(0.0, 1.0));
                let right_scaled = unit(ray(1.0, 0.0));
                let up = up_scaled.normalize_or_zero();
                let right = right_scaled.normalize_or_zero();
                (Mat3::from_cols(right, up, -forward), up_scaled.length())
            }
        }
    }
}

/// One frame's inputs to the sky: what the shader reads as built-ins.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// The camera's orientation and field of view.
    pub view: View,
    /// `POSITION`: the camera's world position in metres.
    pub position: Vec3,
    /// `TIME` in seconds.
    pub time: f32,
    /// `LIGHT0_*` … `LIGHT3_*` ([`SkyLight::toward`], [`SkyLight::from_light`]); a default
    /// light is off.
    pub lights: [SkyLight; 4],
}

impl Default for Frame {
    /// Looking toward −Z with a 90° vertical field of view from the origin at time 0, no light.
    fn default() -> Self {
        Self {
            view: View::Rotation { camera_to_world: Mat3::IDENTITY, fov_y: std::f32::consts::FRAC_PI_2 },
            position: Vec3::ZERO,
            time: 0.0,
            lights: [SkyLight::default(); 4],
        }
    }
}

impl Frame {
    /// The frame of a scene of the vocabulary (the CLI's scene flags and scene files), with its
    /// camera, position, time and lights.
    pub fn from_scene(scene: &skycore::Scene) -> Self {
        let p = scene.camera.position;
        Self {
            view: View::Godot(scene.camera),
            position: Vec3::new(p.x as f32, p.y as f32, p.z as f32),
            time: scene.time as f32,
            lights: scene.lights.map(|light| SkyLight::from_light(&light)),
        }
    }

    /// The full pass's built-ins for a `width`×`height` target.
    pub fn builtins(&self, width: u32, height: u32) -> SkyBuiltins {
        let (basis, tan_half_fov) = self.view.basis(self.position);
        let mut builtins = SkyBuiltins {
            position: self.position.into(),
            time: self.time,
            screen_size: [width as f32, height as f32],
            tan_half_fov,
            lights: self.lights,
            ..SkyBuiltins::default()
        };
        builtins.set_camera_basis(basis.x_axis.into(), basis.y_axis.into(), basis.z_axis.into());
        builtins
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_inverse_view_projection_gives_back_the_rotation_and_fov() {
        let position = Vec3::new(3.0, 2.0, -1.0);
        let camera_to_world = Mat3::from_rotation_y(0.7) * Mat3::from_rotation_x(0.3);
        let fov_y = 1.1_f32;
        let view = Mat4::from_mat3(camera_to_world.transpose()) * Mat4::from_translation(-position);
        // Right-handed perspective projections, depth 0..1 (columns): standard Z with a far
        // plane, and reversed Z with an infinite one.
        let (f, aspect, near, far) = (1.0 / (0.5 * fov_y).tan(), 1.6_f32, 0.1_f32, 100.0_f32);
        let standard = Mat4::from_cols(
            Vec4::new(f / aspect, 0.0, 0.0, 0.0),
            Vec4::new(0.0, f, 0.0, 0.0),
            Vec4::new(0.0, 0.0, far / (near - far), -1.0),
            Vec4::new(0.0, 0.0, near * far / (near - far), 0.0),
        );
        let reversed_infinite = Mat4::from_cols(
            Vec4::new(f / aspect, 0.0, 0.0, 0.0),
            Vec4::new(0.0, f, 0.0, 0.0),
            Vec4::new(0.0, 0.0, 0.0, -1.0),
            Vec4::new(0.0, 0.0, near, 0.0),
        );
        for projection in [standard, reversed_infinite] {
            let (basis, t) = View::InverseViewProjection((projection * view).inverse()).basis(position);
            assert!((t - (0.5 * fov_y).tan()).abs() < 1e-5, "tan(fov/2) {t}");
            for (got, want) in [basis.x_axis, basis.y_axis, basis.z_axis].iter().zip([
                camera_to_world.x_axis,
                camera_to_world.y_axis,
                camera_to_world.z_axis,
            ]) {
                assert!((*got - want).length() < 1e-5, "{got} against {want}");
            }
        }
    }
}
