//! `transfer`'s visibility rays through prtkit's BVH ([`Occluders`]: obvhs' compressed wide BVH)
//! and through Intel Embree 3 (`rtcOccluded1`, the peer issue 32 names), side by side on the same
//! rays: those of a shadowed bake (each vertex's stratified, cosine-weighted directions about its
//! normal, from `x + offset·n`, as `transfer` casts them), for every `stride`-th vertex.
//!
//! `cargo run --release --example visibility_vs_embree -- MESH RAYS STRIDE REPEATS`
//!
//! Embree is loaded at run time (`libloading`, Debian's `libembree-dev` 3.13), so nothing links
//! it at build time; without it the program says so and exits 2. Each tracer's rays per second
//! is the best of REPEATS passes, the two alternating pass after pass, on 1 thread and on 2
//! (rayon pools, the ray list split into the same chunks); each BVH's build time is one build.
//! Both answer occluded or not for every ray: the program reports how many answers differ
//! (single-precision ties at grazing hits). One compact JSON row per figure on stdout.

use glam::DVec3;
use libloading::Library;
use prtkit::mesh::Mesh;
use prtkit::transfer::directions::Stratified;
use prtkit::transfer::visibility::Occluders;
use rayon::prelude::*;
use std::ffi::{c_char, c_void};
use std::time::Instant;

/// Rays per parallel work item, for both tracers.
const CHUNK: usize = 4096;

/// `struct RTCRay` (embree3/rtcore_ray.h): origin, tnear, direction, time, tfar, mask, id, flags.
#[repr(C, align(16))]
struct RtcRay {
    org: [f32; 3],
    tnear: f32,
    dir: [f32; 3],
    time: f32,
    tfar: f32,
    mask: u32,
    id: u32,
    flags: u32,
}

/// `struct RTCIntersectContext` as Debian builds Embree 3.13.5 (RTC_MAX_INSTANCE_LEVEL_COUNT 1,
/// RTC_MIN_WIDTH 0): flags, filter, instID[1].
#[repr(C)]
struct RtcIntersectContext {
    flags: u32,
    filter: *const c_void,
    inst_id: [u32; 1],
}

/// The header's inline `rtcInitIntersectContext`: incoherent rays, no filter, no instance.
fn intersect_context() -> RtcIntersectContext {
    RtcIntersectContext { flags: 0, filter: std::ptr::null(), inst_id: [u32::MAX] }
}

type Handle = *mut c_void;

/// The entry points used, from `libembree3.so.3` (embree3/rtcore_*.h); the library stays loaded
/// as long as they are used.
struct Embree {
    _library: Library,
    new_device: unsafe extern "C" fn(*const c_char) -> Handle,
    new_scene: unsafe extern "C" fn(Handle) -> Handle,
    set_build_quality: unsafe extern "C" fn(Handle, u32),
    new_geometry: unsafe extern "C" fn(Handle, u32) -> Handle,
    set_new_buffer: unsafe extern "C" fn(Handle, u32, u32, u32, usize, usize) -> *mut c_void,
    commit_geometry: unsafe extern "C" fn(Handle),
    attach_geometry: unsafe extern "C" fn(Handle, Handle) -> u32,
    release_geometry: unsafe extern "C" fn(Handle),
    release_scene: unsafe extern "C" fn(Handle),
    release_device: unsafe extern "C" fn(Handle),
    commit_scene: unsafe extern "C" fn(Handle),
    occluded1: unsafe extern "C" fn(Handle, *mut RtcIntersectContext, *mut RtcRay),
}

// embree3/rtcore_{common,geometry,buffer}.h.
const RTC_BUILD_QUALITY_HIGH: u32 = 2;
const RTC_GEOMETRY_TYPE_TRIANGLE: u32 = 0;
const RTC_BUFFER_TYPE_INDEX: u32 = 0;
const RTC_BUFFER_TYPE_VERTEX: u32 = 1;
const RTC_FORMAT_UINT3: u32 = 0x5003;
const RTC_FORMAT_FLOAT3: u32 = 0x9003;

impl Embree {
    fn load() -> Result<Embree, libloading::Error> {
        // SAFETY: loading Embree runs its initialisers only; each symbol is declared with the
        // signature of its prototype in Embree 3's headers.
        unsafe {
            let library = Library::new("libembree3.so.3")?;
            Ok(Embree {
                new_device: *library.get(b"rtcNewDevice\0")?,
                new_scene: *library.get(b"rtcNewScene\0")?,
                set_build_quality: *library.get(b"rtcSetSceneBuildQuality\0")?,
                new_geometry: *library.get(b"rtcNewGeometry\0")?,
                set_new_buffer: *library.get(b"rtcSetNewGeometryBuffer\0")?,
                commit_geometry: *library.get(b"rtcCommitGeometry\0")?,
                attach_geometry: *library.get(b"rtcAttachGeometry\0")?,
                release_geometry: *library.get(b"rtcReleaseGeometry\0")?,
                release_scene: *library.get(b"rtcReleaseScene\0")?,
                release_device: *library.get(b"rtcReleaseDevice\0")?,
                commit_scene: *library.get(b"rtcCommitScene\0")?,
                occluded1: *library.get(b"rtcOccluded1\0")?,
                _library: library,
            })
        }
    }

    /// A committed scene of one triangle mesh, built at high quality (the static scene of a bake).
    fn scene(&self, positions: &[DVec3], triangles: &[[u32; 3]]) -> Scene<'_> {
        // SAFETY: the buffers Embree allocates are filled within their item counts before the
        // geometry is committed; the handles are Embree's own.
        unsafe {
            let device = (self.new_device)(std::ptr::null());
            assert!(!device.is_null(), "rtcNewDevice failed");
            let scene = (self.new_scene)(device);
            (self.set_build_quality)(scene, RTC_BUILD_QUALITY_HIGH);
            let geometry = (self.new_geometry)(device, RTC_GEOMETRY_TYPE_TRIANGLE);
            let v = (self.set_new_buffer)(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 12, positions.len());
            let v = std::slice::from_raw_parts_mut(v as *mut [f32; 3], positions.len());
            v.iter_mut().zip(positions).for_each(|(o, p)| *o = p.as_vec3().to_array());
            let i = (self.set_new_buffer)(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 12, triangles.len());
            std::slice::from_raw_parts_mut(i as *mut [u32; 3], triangles.len()).copy_from_slice(triangles);
            (self.commit_geometry)(geometry);
            (self.attach_geometry)(scene, geometry);
            (self.release_geometry)(geometry);
            (self.commit_scene)(scene);
            Scene { embree: self, device, scene }
        }
    }
}

/// A committed Embree scene; `rtcOccluded1` may be called on it from any thread.
struct Scene<'a> {
    embree: &'a Embree,
    device: Handle,
    scene: Handle,
}

/// The scene and its device are released, which stops Embree's worker threads, before the
/// library can be unloaded (unloading it under running threads crashes at exit).
impl Drop for Scene<'_> {
    fn drop(&mut self) {
        // SAFETY: both handles are Embree's own, released once, after every query returned.
        unsafe {
            (self.embree.release_scene)(self.scene);
            (self.embree.release_device)(self.device);
        }
    }
}

// SAFETY: a committed Embree scene is read-only and its queries are thread-safe (Embree's API
// documentation of rtcCommitScene and rtcOccluded1).
unsafe impl Sync for Scene<'_> {}

impl Scene<'_> {
    fn occluded(&self, ray: &[f32; 6]) -> bool {
        let mut r = RtcRay {
            org: [ray[0], ray[1], ray[2]],
            tnear: 0.0,
            dir: [ray[3], ray[4], ray[5]],
            time: 0.0,
            tfar: f32::INFINITY,
            mask: u32::MAX,
            id: 0,
            flags: 0,
        };
        let mut context = intersect_context();
        // SAFETY: the scene is committed; the ray and context are valid for the call.
        unsafe { (self.embree.occluded1)(self.scene, &mut context, &mut r) };
        r.tfar == f32::NEG_INFINITY
    }
}

/// The rays `transfer --rays RAYS` casts (its default offset, 1e-4 of the diagonal) from every
/// `stride`-th vertex: origin and direction, single precision, as both tracers take them.
fn bake_rays(mesh: &Mesh, rays: usize, stride: usize) -> Vec<[f32; 6]> {
    let directions = Stratified::new(rays, 0);
    let offset = 1e-4 * mesh.extent();
    (0..mesh.positions.len())
        .step_by(stride)
        .flat_map(|v| {
            let (p, n) = (mesh.positions[v], mesh.normals[v]);
            let o = (p + offset * n).as_vec3();
            directions.about(n).map(move |d| {
                let d = d.as_vec3();
                [o.x, o.y, o.z, d.x, d.y, d.z]
            })
        })
        .collect()
}

/// Seconds to answer every ray on a pool of `threads`, and the answers.
fn trace(threads: usize, rays: &[[f32; 6]], occluded: impl Fn(&[f32; 6]) -> bool + Sync) -> (f64, Vec<bool>) {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("a thread pool");
    let start = Instant::now();
    let answers = pool.install(|| rays.par_chunks(CHUNK).flat_map_iter(|c| c.iter().map(&occluded)).collect());
    (start.elapsed().as_secs_f64(), answers)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let [_, mesh, rays, stride, repeats] = args.as_slice() else {
        eprintln!("usage: visibility_vs_embree MESH RAYS STRIDE REPEATS");
        std::process::exit(2);
    };
    let embree = Embree::load().unwrap_or_else(|e| {
        eprintln!("Embree not found ({e}): install libembree-dev (Debian) to compare with it");
        std::process::exit(2);
    });
    let mesh = Mesh::load(std::path::Path::new(mesh)).unwrap_or_else(|e| {
        eprintln!("{e}");
        std::process::exit(2);
    });
    let [rays, stride, repeats] = [rays, stride, repeats].map(|a| a.parse::<usize>().expect("a count"));

    let start = Instant::now();
    let occluders = Occluders::new(&mesh.positions, &mesh.triangles);
    let prtkit_build = start.elapsed().as_secs_f64();
    let start = Instant::now();
    let scene = embree.scene(&mesh.positions, &mesh.triangles);
    let embree_build = start.elapsed().as_secs_f64();
    println!(
        r#"{{"check":"build","vertices":{},"triangles":{},"prtkit_seconds":{prtkit_build},"embree_seconds":{embree_build}}}"#,
        mesh.positions.len(),
        mesh.triangles.len()
    );

    let list = bake_rays(&mesh, rays, stride);
    let ours = |r: &[f32; 6]| {
        let v = |i: usize| DVec3::new(r[i] as f64, r[i + 1] as f64, r[i + 2] as f64);
        occluders.occluded(v(0), v(3))
    };
    let theirs = |r: &[f32; 6]| scene.occluded(r);
    for threads in [1, 2] {
        let (mut best_ours, mut best_theirs) = (f64::INFINITY, f64::INFINITY);
        let mut answers = (Vec::new(), Vec::new());
        for _ in 0..repeats {
            let (t, a) = trace(threads, &list, ours);
            best_ours = best_ours.min(t);
            answers.0 = a;
            let (t, a) = trace(threads, &list, theirs);
            best_theirs = best_theirs.min(t);
            answers.1 = a;
        }
        let n = list.len() as f64;
        let differ = answers.0.iter().zip(&answers.1).filter(|(a, b)| a != b).count();
        let occluded = answers.1.iter().filter(|&&o| o).count() as f64 / n;
        println!(
            r#"{{"check":"trace","threads":{threads},"rays":{},"prtkit_rays_per_second":{},"embree_rays_per_second":{},"ratio":{},"differ":{differ},"differ_fraction":{},"occluded_fraction":{occluded}}}"#,
            list.len(),
            n / best_ours,
            n / best_theirs,
            best_theirs / best_ours,
            differ as f64 / n
        );
    }
}
