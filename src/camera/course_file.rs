//! The course's camera settings file (`-c FILE`), as its `Camera::dump_settings` writes
//! it and `Camera::load_settings` reads it: 30 whitespace-separated numbers,
//!
//! ```text
//! hFov vFov ar nClip fClip            (degrees; ar = screenW/screenH)
//! pos[3] targetPos[3]                 (eye; orbit centre of the viewer)
//! phi theta r minR maxR               (the viewer's orbit, radians)
//! c2w, 3x3 row-major                  (columns: screen x, screen y, direction to the camera)
//! screenW screenH screenDist
//! focalDistance lensRadius
//! ```
//!
//! The course renders from `pos`, `c2w`, `hFov`, `vFov` (and clips rays to
//! `[nClip, fClip]`); the orbit fields and the screen size only drive its OpenGL
//! viewer. ember reads the same fields, checks every one, and renders from the same
//! four without clipping (spec §4). Vectors and the lens are written as the shortest decimals that
//! read back to the same `f32`, angles with full `f64` precision, so a file written
//! by [`CourseCameraFile::from_camera`] reproduces its camera bit for bit.

use super::{output_fov, Camera, ThinLens};
use crate::geometry::Aabb;
use glam::Vec3;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::str::FromStr;

/// The course's near and far clipping distances of the shipped scenes (`znear`, `zfar`).
/// Written for the course's viewer only: ember does not clip.
const COURSE_CLIP: (f64, f64) = (0.1, 100.0);

/// How far `c2w` may be from a rotation (the course writes 6 significant digits).
const ROTATION_TOLERANCE: f32 = 1e-3;

/// A field-of-view aspect within this relative difference of the image's is the image's.
const ASPECT_TOLERANCE: f32 = 1e-4;

/// A camera settings file that cannot be read; the message names the file and the field.
#[derive(Debug, thiserror::Error)]
#[error("{}: {message}", path.display())]
pub struct CameraFileError {
    pub path: PathBuf,
    pub message: String,
}

/// Every field of the course's camera settings file.
#[derive(Clone, Debug, PartialEq)]
pub struct CourseCameraFile {
    pub h_fov: f64,
    pub v_fov: f64,
    pub aspect: f64,
    pub near_clip: f64,
    pub far_clip: f64,
    pub pos: Vec3,
    pub target: Vec3,
    pub phi: f64,
    pub theta: f64,
    pub r: f64,
    pub min_r: f64,
    pub max_r: f64,
    /// Rows of the camera-to-world rotation.
    pub c2w: [Vec3; 3],
    pub screen_w: f64,
    pub screen_h: f64,
    pub screen_dist: f64,
    pub focal_distance: f32,
    pub lens_radius: f32,
}

impl CourseCameraFile {
    /// Reads and checks the file at `path`.
    pub fn read(path: &Path) -> Result<Self, CameraFileError> {
        let text = std::fs::read_to_string(path).map_err(|e| CameraFileError {
            path: path.to_path_buf(),
            message: format!("cannot read camera settings file: {e}"),
        })?;
        Self::parse(&text).map_err(|message| CameraFileError {
            path: path.to_path_buf(),
            message,
        })
    }

    /// Parses and checks the file's text; the error names the offending field.
    pub fn parse(text: &str) -> Result<Self, String> {
        let mut t = Tokens::new(text);
        let f = CourseCameraFile {
            h_fov: t.next("hFov")?,
            v_fov: t.next("vFov")?,
            aspect: t.next("ar")?,
            near_clip: t.next("nClip")?,
            far_clip: t.next("fClip")?,
            pos: t.vec3("pos")?,
            target: t.vec3("targetPos")?,
            phi: t.next("phi")?,
            theta: t.next("theta")?,
            r: t.next("r")?,
            min_r: t.next("minR")?,
            max_r: t.next("maxR")?,
            c2w: [
                t.vec3("c2w row 0")?,
                t.vec3("c2w row 1")?,
                t.vec3("c2w row 2")?,
            ],
            screen_w: t.next("screenW")?,
            screen_h: t.next("screenH")?,
            screen_dist: t.next("screenDist")?,
            focal_distance: t.number("focalDistance")?,
            lens_radius: t.number("lensRadius")?,
        };
        t.end()?;
        f.check()?;
        Ok(f)
    }

    /// The ranges the course assumes but does not check.
    fn check(&self) -> Result<(), String> {
        for (name, deg) in [("hFov", self.h_fov), ("vFov", self.v_fov)] {
            if !(deg > 0.0 && deg < 180.0) {
                return Err(format!(
                    "{name} = {deg}: a field of view must be in (0, 180) degrees"
                ));
            }
        }
        if self.lens_radius < 0.0 {
            return Err(format!(
                "lensRadius = {}: must be at least 0",
                self.lens_radius
            ));
        }
        if self.focal_distance < 0.0 || (self.lens_radius > 0.0 && self.focal_distance == 0.0) {
            return Err(format!(
                "focalDistance = {}: must be positive (at least 0 without a lens)",
                self.focal_distance
            ));
        }
        let [x, y, z] = self.columns();
        let unit = |v: Vec3| (v.length() - 1.0).abs() <= ROTATION_TOLERANCE;
        let orthogonal =
            x.dot(y).abs().max(y.dot(z).abs()).max(z.dot(x).abs()) <= ROTATION_TOLERANCE;
        if !(unit(x) && unit(y) && unit(z) && orthogonal && x.cross(y).dot(z) > 0.0) {
            return Err(
                "c2w is not a rotation: its columns (screen x, screen y, direction to the \
                        camera) must be orthonormal and right-handed"
                    .into(),
            );
        }
        Ok(())
    }

    /// Columns of `c2w`: screen x (right), screen y (up), the direction to the camera (−forward).
    fn columns(&self) -> [Vec3; 3] {
        let [r0, r1, r2] = self.c2w;
        [
            Vec3::new(r0.x, r1.x, r2.x),
            Vec3::new(r0.y, r1.y, r2.y),
            Vec3::new(r0.z, r1.z, r2.z),
        ]
    }

    /// The file's camera for a `width × height` image, and a warning when the file's field
    /// of view has another aspect than the image: the course would stretch the image, ember
    /// widens the field of view to the image's aspect as spec §4 does for scene files.
    pub fn camera(&self, width: u32, height: u32) -> (Camera, Option<String>) {
        let [right, up, to_camera] = self.columns();
        let tx = ((self.h_fov.to_radians() * 0.5).tan()) as f32;
        let ty = ((self.v_fov.to_radians() * 0.5).tan()) as f32;
        let a = width as f32 / height as f32;
        let (mut tan_half_x, mut tan_half_y, mut warning) = (tx, ty, None);
        if ((tx / ty) / a - 1.0).abs() > ASPECT_TOLERANCE {
            (tan_half_x, tan_half_y) = output_fov(Some(tx), Some(ty), a);
            warning = Some(format!(
                "the camera file's field of view ({:.4}° x {:.4}°) has aspect {:.4}, the image \
                 {width}x{height} has {a:.4}: the field of view is widened to the image's aspect",
                self.h_fov,
                self.v_fov,
                tx / ty
            ));
        }
        let camera = Camera {
            eye: self.pos,
            forward: -to_camera,
            up,
            right,
            tan_half_x,
            tan_half_y,
            width,
            height,
            lens: ThinLens {
                radius: self.lens_radius,
                focal_distance: self.focal_distance,
            },
        };
        (camera, warning)
    }

    /// The file the course's viewer would write for `camera`, with its orbit around the
    /// centre of `bounds` as the course places it (radius = distance to the eye, zoom
    /// limits 1/20 and 10 times that).
    pub fn from_camera(camera: &Camera, bounds: &Aabb) -> Self {
        let target = if bounds.is_empty() {
            Vec3::ZERO
        } else {
            bounds.centre()
        };
        let to_camera = -camera.forward;
        let r = (camera.eye - target).length() as f64;
        let (w, h) = (camera.width as f64, camera.height as f64);
        let (right, up) = (camera.right, camera.up);
        CourseCameraFile {
            h_fov: 2.0 * (camera.tan_half_x as f64).atan().to_degrees(),
            v_fov: 2.0 * (camera.tan_half_y as f64).atan().to_degrees(),
            aspect: w / h,
            near_clip: COURSE_CLIP.0,
            far_clip: COURSE_CLIP.1,
            pos: camera.eye,
            target,
            phi: (to_camera.y as f64).clamp(-1.0, 1.0).acos(),
            theta: (to_camera.x as f64).atan2(to_camera.z as f64),
            r,
            min_r: r / 20.0,
            max_r: r * 10.0,
            c2w: [
                Vec3::new(right.x, up.x, to_camera.x),
                Vec3::new(right.y, up.y, to_camera.y),
                Vec3::new(right.z, up.z, to_camera.z),
            ],
            screen_w: w,
            screen_h: h,
            screen_dist: h / (2.0 * camera.tan_half_y as f64),
            focal_distance: camera.lens.focal_distance,
            lens_radius: camera.lens.radius,
        }
    }

    /// The file's text, in the course's six lines.
    pub fn to_text(&self) -> String {
        let v = |v: Vec3| format!("{} {} {}", v.x, v.y, v.z);
        let mut s = String::new();
        let _ = writeln!(
            s,
            "{} {} {} {} {}",
            self.h_fov, self.v_fov, self.aspect, self.near_clip, self.far_clip
        );
        let _ = writeln!(s, "{} {}", v(self.pos), v(self.target));
        let _ = writeln!(
            s,
            "{} {} {} {} {}",
            self.phi, self.theta, self.r, self.min_r, self.max_r
        );
        let [r0, r1, r2] = self.c2w;
        let _ = writeln!(s, "{} {} {}", v(r0), v(r1), v(r2));
        let _ = writeln!(
            s,
            "{} {} {}",
            self.screen_w, self.screen_h, self.screen_dist
        );
        let _ = writeln!(s, "{} {}", self.focal_distance, self.lens_radius);
        s
    }
}

/// The file's numbers in order, with their line numbers for error messages.
struct Tokens<'a> {
    words: Vec<(usize, &'a str)>,
    next: usize,
}

impl<'a> Tokens<'a> {
    fn new(text: &'a str) -> Self {
        let words = text
            .lines()
            .enumerate()
            .flat_map(|(i, l)| l.split_whitespace().map(move |w| (i + 1, w)))
            .collect();
        Tokens { words, next: 0 }
    }

    /// The next number, read as `T` (vectors as `f32`, so their decimals round once).
    fn number<T: FromStr + Into<f64> + Copy>(&mut self, name: &str) -> Result<T, String> {
        let Some(&(line, word)) = self.words.get(self.next) else {
            return Err(format!(
                "field {name} (number {} of 30) is missing: the file ends early",
                self.next + 1
            ));
        };
        self.next += 1;
        match word.parse::<T>() {
            Ok(x) if x.into().is_finite() => Ok(x),
            _ => Err(format!(
                "field {name} (number {} of 30, line {line}): expected a finite number, got {word:?}",
                self.next
            )),
        }
    }

    fn next(&mut self, name: &str) -> Result<f64, String> {
        self.number::<f64>(name)
    }

    fn vec3(&mut self, name: &str) -> Result<Vec3, String> {
        let mut v = [0f32; 3];
        for (i, c) in v.iter_mut().enumerate() {
            *c = self.number::<f32>(&format!("{name}[{i}]"))?;
        }
        Ok(Vec3::from(v))
    }

    fn end(&self) -> Result<(), String> {
        match self.words.get(self.next) {
            None => Ok(()),
            Some(&(line, word)) => Err(format!(
                "unexpected {word:?} on line {line} after the 30 fields (lensRadius is the last)"
            )),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::CameraDesc;

    fn default_camera() -> (Camera, Aabb) {
        let b = Aabb::new(Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 2.0, 1.3));
        let desc = CameraDesc {
            forward: Vec3::new(0.1, -0.2, -1.0).normalize(),
            ..CameraDesc::default()
        };
        let mut desc = desc;
        desc.up = (Vec3::Y - desc.forward * desc.forward.y).normalize();
        (Camera::new(&desc, &b, 480, 360), b)
    }

    #[test]
    fn round_trip_is_bit_exact() {
        let (cam, b) = default_camera();
        let text = CourseCameraFile::from_camera(&cam, &b).to_text();
        let (back, warning) = CourseCameraFile::parse(&text).unwrap().camera(480, 360);
        assert_eq!(warning, None);
        assert_eq!(back, cam, "{text}");
    }

    #[test]
    fn orbit_fields_place_the_eye_as_the_course_does() {
        // The course: pos = target + r·(sin φ sin θ, cos φ, sin φ cos θ).
        let (cam, b) = default_camera();
        let f = CourseCameraFile::from_camera(&cam, &b);
        let d = Vec3::new(
            (f.phi.sin() * f.theta.sin()) as f32,
            f.phi.cos() as f32,
            (f.phi.sin() * f.theta.cos()) as f32,
        );
        assert!((f.target + f.r as f32 * d - cam.eye).length() < 1e-5);
    }

    #[test]
    fn course_written_file_is_read() {
        // Six significant digits, trailing spaces, as the course's dump_settings writes.
        let text = "49.1343 37.8493 1.33333 0.1 100\n0 1 5.5 0 1 0 \n1.5708 0 4.5 0.225 90\n\
                    1 0 0 0 1 0 0 0 1 \n480 360 519.615\n4.7 0\n";
        let f = CourseCameraFile::parse(text).unwrap();
        let (cam, warning) = f.camera(480, 360);
        assert_eq!(warning, None);
        assert_eq!(cam.eye, Vec3::new(0.0, 1.0, 5.5));
        assert_eq!(cam.forward, Vec3::NEG_Z);
        assert!((cam.tan_half_x - (49.1343f32.to_radians() / 2.0).tan()).abs() < 1e-6);
        assert!(cam.lens.is_pinhole());
    }

    #[test]
    fn errors_name_the_field() {
        let good = "40 30 1.333 0.1 100\n0 0 5 0 0 0\n1.57 0 5 0.25 50\n1 0 0 0 1 0 0 0 1\n\
                    4 3 2\n4.7 0\n";
        assert!(CourseCameraFile::parse(good).is_ok());
        let cases = [
            (good.replace("1.57", "x"), "phi"),
            (good.replace("4.7 0\n", "4.7\n"), "lensRadius"),
            (good.replace("40 30", "40 nan"), "vFov"),
            (good.replace("40 30", "190 30"), "hFov"),
            (good.replace("1 0 0 0 1 0", "1 0 0 0 2 0"), "c2w"),
            (
                good.replace("1 0 0 0 1 0 0 0 1", "-1 0 0 0 1 0 0 0 1"),
                "c2w",
            ),
            (good.replace("4.7 0", "4.7 -1"), "lensRadius"),
            (good.replace("4.7 0", "4.7 0 7"), "after the 30 fields"),
            (good.replace("0 0 5 0", "0 0 1e999 0"), "pos[2]"),
        ];
        for (text, name) in cases {
            let e = CourseCameraFile::parse(&text).unwrap_err();
            assert!(e.contains(name), "{e}");
            assert!(!e.contains('\n'), "{e}");
        }
    }

    #[test]
    fn other_aspect_widens_and_warns() {
        let (cam, b) = default_camera();
        let f = CourseCameraFile::from_camera(&cam, &b);
        let (wide, warning) = f.camera(480, 240);
        assert!(warning.is_some());
        assert_eq!(wide.tan_half_y, cam.tan_half_y);
        assert!((wide.tan_half_x / wide.tan_half_y - 2.0).abs() < 1e-6);
    }
}
