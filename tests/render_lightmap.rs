//! `render --shading transfer --lightmap FILE.exr` refuses lightmaps that cannot relight the
//! `--transfer` bake (issue 32; the campaign rules of issue 34): a missing file, a file that is
//! not an EXR, an EXR without the layers T0 … T{n²−1} of the bake's order, layers of different
//! sizes (the parts of a multi-part EXR may differ), and a NaN or infinite transfer value. Each
//! exits 2 naming the lightmap's file, says what is wrong, and writes no image. The lightmap
//! `transfer` wrote itself relights (the control).

mod common;

use common::{cmd, stderr};
use exr::prelude::{
    AnyChannel, AnyChannels, Encoding, FlatSamples, Image, ImageAttributes, IntegerBounds, Layer, LayerAttributes,
    Text, WritableImage,
};
use std::path::Path;

/// An EXR of grey layers, one part each, named by layer: `(name, width, height, samples)`.
fn write_parts(path: &Path, parts: &[(&str, usize, usize, Vec<f32>)]) {
    let layers: Vec<Layer<AnyChannels<FlatSamples>>> = parts
        .iter()
        .map(|(name, w, h, samples)| {
            let channel = AnyChannel::new(Text::from("Y"), FlatSamples::F32(samples.clone()));
            let attributes = LayerAttributes::named(Text::from(*name));
            Layer::new((*w, *h), attributes, Encoding::UNCOMPRESSED, AnyChannels::sort(vec![channel].into()))
        })
        .collect();
    let size = (parts[0].1, parts[0].2);
    Image::from_layers(
        ImageAttributes::new(IntegerBounds::from_dimensions(size)),
        exr::prelude::SmallVec::from_vec(layers),
    )
    .write()
    .to_file(path)
    .unwrap();
}

#[test]
fn lightmaps_that_cannot_relight_the_bake_exit_2_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    common::sky_pfm(dir.path(), 32, 16);
    let mesh = Path::new(env!("CARGO_MANIFEST_DIR")).join("testdata/meshes/floor-ball.obj");
    let bake = |order: &str, tag: &str| {
        let out = cmd("transfer")
            .arg(&mesh)
            .args(["--mode", "unshadowed", "--albedo", "0.8", "-n", order, "-q", "--glb", &format!("{tag}.glb"), "-o"])
            .arg(format!("{tag}.json"))
            .args(["--lightmap", "8x8", &format!("{tag}.exr")])
            .current_dir(dir.path())
            .output()
            .unwrap();
        assert!(out.status.success(), "transfer -n {order}: {}", stderr(&out));
    };
    bake("3", "n3");
    bake("2", "n2");
    std::fs::write(dir.path().join("text.exr"), "T0 T1 T2\n").unwrap();
    let grey = |value: f32, side: usize| vec![value; side * side];
    // T0 8×8, the other eight 4×4.
    let parts: Vec<(String, usize, usize, Vec<f32>)> =
        (0..9).map(|i| (format!("T{i}"), 8 >> (i.min(1)), 8 >> (i.min(1)), grey(0.1, 8 >> (i.min(1))))).collect();
    let parts: Vec<(&str, usize, usize, Vec<f32>)> =
        parts.iter().map(|(n, w, h, s)| (n.as_str(), *w, *h, s.clone())).collect();
    write_parts(&dir.path().join("sizes.exr"), &parts);
    let mut with_nan: Vec<(&str, usize, usize, Vec<f32>)> =
        parts.iter().map(|(n, _, _, _)| (*n, 8, 8, grey(0.1, 8))).collect();
    with_nan[5].3[8 * 3 + 2] = f32::NAN;
    write_parts(&dir.path().join("nan.exr"), &with_nan);
    let sky_exr = dir.path().join("sky.exr");
    let out =
        cmd("prtkit").args(["convert", "sky.pfm", "-o", "sky.exr", "-q"]).current_dir(dir.path()).output().unwrap();
    assert!(out.status.success() && sky_exr.exists(), "{}", stderr(&out));

    let cases: [(&str, &str); 6] = [
        ("absent.exr", "absent.exr"),
        ("text.exr", "OpenEXR magic number"),
        ("sky.exr", "no layer T0: not a lightmap of order 3 (transfer --lightmap writes one)"),
        ("n2.exr", "no layer T4: not a lightmap of order 3"),
        ("sizes.exr", "layer T1 is 4x4, layer T0 is 8x8: a lightmap's layers are one size"),
        ("nan.exr", "layer T5 texel (2, 3) is NaN: transfer values are finite"),
    ];
    let render = |lightmap: &str| {
        cmd("render")
            .args(["sky.pfm", "--scene"])
            .arg(&mesh)
            .args(["--brdf", "lambert:albedo=0.8", "--res", "24x24", "--shading", "transfer"])
            .args(["--transfer", "n3.glb", "--lightmap", lightmap, "-q", "-o", "out.exr"])
            .current_dir(dir.path())
            .output()
            .unwrap()
    };
    for (lightmap, reason) in cases {
        let out = render(lightmap);
        let message = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{lightmap}: {message}");
        assert!(message.contains(lightmap) && message.contains(reason), "{lightmap}: {message}");
        assert!(!message.contains("panicked"), "{lightmap}: {message}");
        assert!(!dir.path().join("out.exr").exists(), "{lightmap}: an image was written");
    }
    // The control: the lightmap of the bake's own order relights it.
    let out = render("n3.exr");
    assert!(out.status.success() && dir.path().join("out.exr").exists(), "{}", stderr(&out));
}
