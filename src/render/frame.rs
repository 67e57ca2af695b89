//! The render loop: one primary ray per pixel centre, shading where it hits, the environment
//! (bilinear lookup) where it does not.

use super::{Camera, Hit, Scene};
use crate::envmap::EnvMap;
use crate::io::RgbImage;
use crate::progress::Progress;
use glam::{DMat3, DVec3};
use rayon::prelude::*;

/// A shading mode: outgoing radiance at a hit towards `wo` (unit, towards the viewer).
pub trait Shade: Sync {
    /// Linear RGB radiance.
    fn shade(&self, hit: &Hit, wo: DVec3) -> [f64; 3];
}

/// Two shading modes' radiance added (e.g. a smooth part and the bright sources' exact part).
pub struct Sum<'a>(pub &'a dyn Shade, pub &'a dyn Shade);

impl Shade for Sum<'_> {
    fn shade(&self, hit: &Hit, wo: DVec3) -> [f64; 3] {
        let (a, b) = (self.0.shade(hit, wo), self.1.shade(hit, wo));
        [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
    }
}

/// A rendered image and which pixels show the object.
#[derive(Clone, Debug)]
pub struct Frame {
    /// Linear RGB.
    pub image: RgbImage,
    /// `true` where the pixel centre's ray hits the object.
    pub mask: Vec<bool>,
}

/// Renders `scene` through `camera` with `shader`, the environment behind.
pub fn render(scene: &Scene, camera: &Camera, env: &EnvMap, shader: &dyn Shade, progress: &dyn Progress) -> Frame {
    render_turned(scene, camera, env, DMat3::IDENTITY, shader, progress)
}

/// [`render`] under the environment turned by `rotation`, L'(ω) = L(R⁻¹ω) (the turn the
/// shader applies to its lighting, `render --env-rotation`): the background the camera sees
/// along d is the map's radiance along Rᵀd, so that it matches what lights the object.
pub fn render_turned(
    scene: &Scene,
    camera: &Camera,
    env: &EnvMap,
    rotation: DMat3,
    shader: &dyn Shade,
    progress: &dyn Progress,
) -> Frame {
    let from_turned = rotation.transpose();
    let (w, h) = (camera.width, camera.height);
    progress.start("render", h as u64);
    let rows: Vec<(Vec<[f32; 3]>, Vec<bool>)> = (0..h)
        .into_par_iter()
        .map(|y| {
            let mut px = Vec::with_capacity(w);
            let mut mask = Vec::with_capacity(w);
            for x in 0..w {
                let d = camera.ray(x, y);
                match scene.intersect(camera.eye, d) {
                    Some(hit) => {
                        let c = shader.shade(&hit, -d);
                        px.push([c[0] as f32, c[1] as f32, c[2] as f32]);
                        mask.push(true);
                    }
                    None => {
                        px.push(env.lookup(from_turned * d));
                        mask.push(false);
                    }
                }
            }
            progress.advance(1);
            (px, mask)
        })
        .collect();
    progress.finish();
    let mut image = RgbImage::new(w, h);
    let mut mask = Vec::with_capacity(w * h);
    for (y, (px, m)) in rows.into_iter().enumerate() {
        image.pixels[y * w..(y + 1) * w].copy_from_slice(&px);
        mask.extend(m);
    }
    Frame { image, mask }
}
