//! Base colours read from meshes (issue 32, the albedo of `transfer`): `Mesh::load_coloured` on
//! glTF 2.0, PLY and OBJ, against values derived here by hand, from the specifications, without
//! the reader's code:
//!
//! - glTF COLOR_0 as float VEC3, normalized unsigned byte VEC4 and normalized unsigned short VEC3
//!   (glTF 2.0 §3.7.2.1, §3.11: c / (2ⁿ − 1), linear), times baseColorFactor, times the base-colour
//!   texture (§3.9.2);
//! - a 4×4 PNG of known sRGB codes sampled at texel centres (the texel, decoded), between texels
//!   (the mean of the *linear* values, which filtering the codes would miss by far), and outside
//!   [0, 1] under REPEAT, CLAMP_TO_EDGE and MIRRORED_REPEAT, the texel each case reads worked out
//!   by hand from the modes' definitions (OpenGL 4.6 §8.14.2);
//! - the same asset as .gltf (data: URIs), .glb (the image in a bufferView) and .gltf with an
//!   external .png; a missing image, a missing texCoord set, KHR_texture_transform and a huge
//!   image are errors naming the file and the texture, while `Mesh::load` reads the mesh;
//! - PLY `uchar` colours (sRGB-decoded) and `float` colours (linear), a PLY without colours and an
//!   OBJ are errors; vertex order is `Mesh::load`'s; garbled files are errors, never panics.

use base64::Engine as _;
use prtkit::mesh::Mesh;
use std::path::{Path, PathBuf};

/// sRGB-encoded code → linear (IEC 61966-2-1, written out here apart from the library's).
fn lin(code: u32, max: u32) -> f64 {
    let c = code as f64 / max as f64;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

fn close(a: [f64; 3], b: [f64; 3], tol: f64) -> bool {
    (0..3).all(|k| (a[k] - b[k]).abs() <= tol)
}

#[track_caller]
fn assert_colours(got: &[[f64; 3]], want: &[[f64; 3]], tol: f64, what: &str) {
    assert_eq!(got.len(), want.len(), "{what}: vertex count");
    for (i, (g, w)) in got.iter().zip(want).enumerate() {
        assert!(close(*g, *w, tol), "{what}: vertex {i}: got {g:?}, want {w:?}");
    }
}

// ---------------------------------------------------------------------------------------------
// A glTF asset written by hand.
// ---------------------------------------------------------------------------------------------

const FLOAT: u32 = 5126;
const UBYTE: u32 = 5121;
const USHORT: u32 = 5123;

/// A glTF asset assembled field by field: one buffer, a view per accessor or image, one mesh of
/// the primitives added, one node.
#[derive(Default)]
struct Asset {
    bin: Vec<u8>,
    views: Vec<String>,
    accessors: Vec<String>,
    primitives: Vec<String>,
    /// Top-level members (materials, textures, images, samplers), JSON text with a leading comma.
    top: String,
}

fn f32_bytes(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

impl Asset {
    fn view(&mut self, bytes: &[u8]) -> usize {
        while self.bin.len() % 4 != 0 {
            self.bin.push(0);
        }
        let offset = self.bin.len();
        self.bin.extend_from_slice(bytes);
        self.views.push(format!(r#"{{"buffer": 0, "byteOffset": {offset}, "byteLength": {}}}"#, bytes.len()));
        self.views.len() - 1
    }

    fn accessor(&mut self, bytes: &[u8], component: u32, count: usize, ty: &str, normalized: bool) -> usize {
        let view = self.view(bytes);
        let mut a =
            format!(r#"{{"bufferView": {view}, "componentType": {component}, "count": {count}, "type": "{ty}""#);
        if normalized {
            a.push_str(r#", "normalized": true"#);
        }
        a.push('}');
        self.accessors.push(a);
        self.accessors.len() - 1
    }

    /// A primitive of `n` vertices (three a triangle) spread on a helix, with `attributes`
    /// (name, accessor) besides POSITION, and `material` (an index) when given.
    fn primitive(&mut self, n: usize, attributes: &[(&str, usize)], material: Option<usize>) {
        assert_eq!(n % 3, 0);
        let positions: Vec<f32> = (0..n)
            .flat_map(|i| {
                let t = i as f32 + 0.3 * self.primitives.len() as f32;
                [t.cos(), t.sin(), 0.1 * t]
            })
            .collect();
        // POSITION has its bounds (§3.7.2.1 requires min and max).
        let view = self.view(&f32_bytes(&positions));
        self.accessors.push(format!(
            r#"{{"bufferView": {view}, "componentType": {FLOAT}, "count": {n}, "type": "VEC3", "min": [-100, -100, -100], "max": [100, 100, 100]}}"#
        ));
        let position = self.accessors.len() - 1;
        let mut attrs = format!(r#""POSITION": {position}"#);
        for (name, a) in attributes {
            attrs.push_str(&format!(r#", "{name}": {a}"#));
        }
        let material = material.map(|m| format!(r#", "material": {m}"#)).unwrap_or_default();
        self.primitives.push(format!(r#"{{"attributes": {{{attrs}}}{material}}}"#));
    }

    fn json(&self, buffer: &str) -> String {
        format!(
            r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0]}}], "nodes": [{{"mesh": 0}}],
 "meshes": [{{"primitives": [{}]}}],
 "accessors": [{}],
 "bufferViews": [{}],
 "buffers": [{buffer}]{}}}"#,
            self.primitives.join(", "),
            self.accessors.join(", "),
            self.views.join(", "),
            self.top
        )
    }

    /// As `.gltf` with its buffer in a data: URI.
    fn write_gltf(&self, path: &Path) -> PathBuf {
        let data = base64::engine::general_purpose::STANDARD.encode(&self.bin);
        let buffer =
            format!(r#"{{"byteLength": {}, "uri": "data:application/octet-stream;base64,{data}"}}"#, self.bin.len());
        std::fs::write(path, self.json(&buffer)).unwrap();
        path.to_path_buf()
    }

    /// As `.glb` (glTF 2.0 §4.4): header, JSON chunk padded with spaces, BIN chunk with zeros.
    fn write_glb(&self, path: &Path) -> PathBuf {
        let mut json = self.json(&format!(r#"{{"byteLength": {}}}"#, self.bin.len())).into_bytes();
        while json.len() % 4 != 0 {
            json.push(b' ');
        }
        let mut bin = self.bin.clone();
        while bin.len() % 4 != 0 {
            bin.push(0);
        }
        let total = 12 + 8 + json.len() + 8 + bin.len();
        let mut out = b"glTF".to_vec();
        out.extend(2u32.to_le_bytes());
        out.extend((total as u32).to_le_bytes());
        out.extend((json.len() as u32).to_le_bytes());
        out.extend(0x4E4F_534Au32.to_le_bytes());
        out.extend(json);
        out.extend((bin.len() as u32).to_le_bytes());
        out.extend(0x004E_4942u32.to_le_bytes());
        out.extend(bin);
        std::fs::write(path, out).unwrap();
        path.to_path_buf()
    }

    /// A float VEC2 UV accessor.
    fn uvs(&mut self, uvs: &[[f64; 2]]) -> usize {
        let flat: Vec<f32> = uvs.iter().flatten().map(|&x| x as f32).collect();
        self.accessor(&f32_bytes(&flat), FLOAT, uvs.len(), "VEC2", false)
    }
}

// ---------------------------------------------------------------------------------------------
// The texture: 4×4 sRGB codes, every texel different, neighbours far apart.
// ---------------------------------------------------------------------------------------------

const W: usize = 4;

/// The sRGB code of texel (column i, row j from the top).
fn code(i: usize, j: usize) -> [u8; 3] {
    [[0, 255, 64, 192][i], [255, 0, 128, 32][j], (16 * (4 * i + j) + 8) as u8]
}

/// Texel (i, j) decoded to linear.
fn texel(i: usize, j: usize) -> [f64; 3] {
    code(i, j).map(|c| lin(c as u32, 255))
}

fn png(width: usize, height: usize, codes: impl Fn(usize, usize) -> [u8; 3]) -> Vec<u8> {
    let img = image::RgbImage::from_fn(width as u32, height as u32, |x, y| image::Rgb(codes(x as usize, y as usize)));
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png).unwrap();
    out.into_inner()
}

/// A weighted sum of texels: (i, j, weight).
fn mix(terms: &[(usize, usize, f64)]) -> [f64; 3] {
    let mut c = [0.0; 3];
    for &(i, j, w) in terms {
        let t = texel(i, j);
        for k in 0..3 {
            c[k] += w * t[k];
        }
    }
    c
}

/// UV of the point x texels right and y texels down from the top-left corner's texel centre
/// scale: u = (x + ½)/W, so x = 0 is the centre of column 0.
fn at(x: f64, y: f64) -> [f64; 2] {
    [(x + 0.5) / W as f64, (y + 0.5) / W as f64]
}

/// The vertices of the filtering test and the colour each must read (weights by hand: at a
/// texel centre the texel; halfway, ½ and ½; at a quarter, ¾ and ¼).
fn filtering_cases() -> Vec<([f64; 2], [f64; 3])> {
    let mut cases = Vec::new();
    for i in 0..W {
        for j in 0..W {
            cases.push((at(i as f64, j as f64), texel(i, j)));
        }
    }
    for i in 0..W - 1 {
        for j in 0..W - 1 {
            cases.push((at(i as f64 + 0.5, j as f64), mix(&[(i, j, 0.5), (i + 1, j, 0.5)])));
            cases.push((at(i as f64, j as f64 + 0.5), mix(&[(i, j, 0.5), (i, j + 1, 0.5)])));
            cases.push((
                at(i as f64 + 0.5, j as f64 + 0.5),
                mix(&[(i, j, 0.25), (i + 1, j, 0.25), (i, j + 1, 0.25), (i + 1, j + 1, 0.25)]),
            ));
            cases.push((
                at(i as f64 + 0.25, j as f64 + 0.75),
                mix(&[
                    (i, j, 0.75 * 0.25),
                    (i + 1, j, 0.25 * 0.25),
                    (i, j + 1, 0.75 * 0.75),
                    (i + 1, j + 1, 0.25 * 0.75),
                ]),
            ));
        }
    }
    cases
}

/// Pads a vertex list to whole triangles by repeating its first vertex.
fn pad<T: Clone>(mut v: Vec<T>) -> Vec<T> {
    while v.len() % 3 != 0 {
        v.push(v[0].clone());
    }
    v
}

/// A textured asset: one primitive whose TEXCOORD_0 are `uvs`, material 0 with the texture
/// (sampler `sampler`: JSON or "" for none) of image 0 at `image` (JSON of the image).
fn textured(uvs: &[[f64; 2]], sampler: &str, image: &str, factor: &str) -> Asset {
    let mut a = Asset::default();
    let uv = a.uvs(uvs);
    a.primitive(uvs.len(), &[("TEXCOORD_0", uv)], Some(0));
    let (samplers, reference) = match sampler {
        "" => (String::new(), String::new()),
        s => (format!(r#", "samplers": [{s}]"#), r#", "sampler": 0"#.to_string()),
    };
    a.top = format!(
        r#", "materials": [{{"pbrMetallicRoughness": {{"baseColorTexture": {{"index": 0}}{factor}}}}}],
 "textures": [{{"source": 0{reference}}}], "images": [{image}]{samplers}"#
    );
    a
}

fn png_uri(bytes: &[u8]) -> String {
    format!(r#"{{"uri": "data:image/png;base64,{}"}}"#, base64::engine::general_purpose::STANDARD.encode(bytes))
}

#[test]
fn the_srgb_oracle_matches_published_values() {
    // IEC 61966-2-1 tables: code 128 is 0.2158605 linear, code 188 0.5028865, code 10 0.0030353.
    assert!((lin(128, 255) - 0.215_860_5).abs() < 1e-7);
    assert!((lin(188, 255) - 0.502_886_5).abs() < 1e-7);
    assert!((lin(10, 255) - 0.003_035_3).abs() < 1e-7);
    assert_eq!((lin(0, 255), lin(255, 255)), (0.0, 1.0));
}

#[test]
fn a_texture_is_filtered_in_linear_values_at_its_texel_centres() {
    let dir = tempfile::tempdir().unwrap();
    let cases = pad(filtering_cases());
    let uvs: Vec<[f64; 2]> = cases.iter().map(|c| c.0).collect();
    let want: Vec<[f64; 3]> = cases.iter().map(|c| c.1).collect();
    let image = png(W, W, code);
    let asset = textured(&uvs, "", &png_uri(&image), "");
    let gltf = asset.write_gltf(&dir.path().join("t.gltf"));
    let mesh = Mesh::load_coloured(&gltf).unwrap();
    // f32 UVs: a texel centre such as 0.375 is exact in f32, and so are the quarter points of a
    // 4-texel image; the products are in f64.
    assert_colours(mesh.base_colors.as_ref().unwrap(), &want, 1e-12, "data: URI");

    // Filtering the sRGB codes and decoding the result (the wrong order) misses by far: halfway
    // between red codes 0 and 255 it gives 0.214 where the linear mean is 0.5.
    let wrong = lin(128, 255);
    let halfway = mesh.base_colors.as_ref().unwrap()[16][0];
    assert!((halfway - 0.5).abs() < 1e-12 && (halfway - wrong).abs() > 0.28, "{halfway} vs {wrong}");

    // The same asset as .glb, the PNG in a bufferView: the same colours, bit for bit.
    let mut glb_asset = textured(&uvs, "", r#"{"bufferView": 0, "mimeType": "image/png"}"#, "");
    let view = glb_asset.view(&image);
    glb_asset.top =
        glb_asset.top.replace(r#""bufferView": 0, "mimeType""#, &format!(r#""bufferView": {view}, "mimeType""#));
    let glb = glb_asset.write_glb(&dir.path().join("t.glb"));
    let from_glb = Mesh::load_coloured(&glb).unwrap();
    assert_eq!(from_glb.base_colors, mesh.base_colors);

    // And with the PNG beside the .gltf, named by a relative path with a percent-escape.
    std::fs::create_dir(dir.path().join("tex")).unwrap();
    std::fs::write(dir.path().join("tex/base colour.png"), &image).unwrap();
    let external = textured(&uvs, "", r#"{"uri": "tex/base%20colour.png"}"#, "");
    let path = external.write_gltf(&dir.path().join("external.gltf"));
    assert_eq!(Mesh::load_coloured(&path).unwrap().base_colors, mesh.base_colors);

    // The vertex order is Mesh::load's, and Mesh::load reads no colour.
    let plain = Mesh::load(&gltf).unwrap();
    assert_eq!(plain.positions, mesh.positions);
    assert_eq!(plain.triangles, mesh.triangles);
    assert!(plain.base_colors.is_none());
}

#[test]
fn uvs_outside_the_unit_square_wrap_by_the_samplers_modes() {
    // (texel coordinates x, y of the UV, as in `at`; the texel each mode reads, by hand:
    // REPEAT takes the index mod 4; CLAMP_TO_EDGE clamps it to 0..3; MIRRORED_REPEAT repeats
    // 0 1 2 3 3 2 1 0 with period 8, so index 4 is 3, 5 is 2, −1 is 0, −2 is 1.)
    // Each case is along u with the row centre 1, then the same along v with column centre 2.
    type Case = (f64, [&'static [(usize, f64)]; 3]);
    let cases: [Case; 7] = [
        (5.0, [&[(1, 1.0)], &[(3, 1.0)], &[(2, 1.0)]]),
        (-2.0, [&[(2, 1.0)], &[(0, 1.0)], &[(1, 1.0)]]),
        (9.0, [&[(1, 1.0)], &[(3, 1.0)], &[(1, 1.0)]]),
        (-5.0, [&[(3, 1.0)], &[(0, 1.0)], &[(3, 1.0)]]),
        // u = 0: halfway between index −1 and 0.
        (-0.5, [&[(3, 0.5), (0, 0.5)], &[(0, 1.0)], &[(0, 1.0)]]),
        // u = 1: halfway between index 3 and 4.
        (3.5, [&[(3, 0.5), (0, 0.5)], &[(3, 1.0)], &[(3, 1.0)]]),
        // u = 1.75: texel coordinate 1.75·4 − ½ = 6.5 → indices 6 and 7, ½ each.
        (6.5, [&[(2, 0.5), (3, 0.5)], &[(3, 1.0)], &[(1, 0.5), (0, 0.5)]]),
    ];
    let dir = tempfile::tempdir().unwrap();
    let image = png(W, W, code);
    for (mode, (gl, name)) in
        [(10497, "REPEAT"), (33071, "CLAMP_TO_EDGE"), (33648, "MIRRORED_REPEAT")].iter().enumerate()
    {
        let mut uvs = Vec::new();
        let mut want = Vec::new();
        for (x, reads) in &cases {
            uvs.push(at(*x, 1.0));
            want.push(mix(&reads[mode].iter().map(|&(i, w)| (i, 1, w)).collect::<Vec<_>>()));
            uvs.push(at(2.0, *x));
            want.push(mix(&reads[mode].iter().map(|&(j, w)| (2, j, w)).collect::<Vec<_>>()));
        }
        let (uvs, want) = (pad(uvs), pad(want));
        let sampler = format!(r#"{{"wrapS": {gl}, "wrapT": {gl}}}"#);
        let path = textured(&uvs, &sampler, &png_uri(&image), "").write_gltf(&dir.path().join(format!("{name}.gltf")));
        let mesh = Mesh::load_coloured(&path).unwrap();
        assert_colours(mesh.base_colors.as_ref().unwrap(), &want, 1e-12, name);
        if *gl == 10497 {
            // A texture without sampler repeats (§3.8.4): the same colours.
            let path = textured(&uvs, "", &png_uri(&image), "").write_gltf(&dir.path().join("default.gltf"));
            assert_colours(Mesh::load_coloured(&path).unwrap().base_colors.as_ref().unwrap(), &want, 1e-12, "default");
        }
    }
    // s and t wrap apart: u mirrored, v clamped.
    let uvs = pad(vec![at(5.0, -2.0), at(-2.0, 5.0)]);
    let sampler = r#"{"wrapS": 33648, "wrapT": 33071}"#;
    let path = textured(&uvs, sampler, &png_uri(&image), "").write_gltf(&dir.path().join("mixed.gltf"));
    let want = pad(vec![texel(2, 0), texel(1, 3)]);
    assert_colours(Mesh::load_coloured(&path).unwrap().base_colors.as_ref().unwrap(), &want, 1e-12, "mixed");
}

#[test]
fn colour_0_is_linear_in_every_encoding_and_multiplies_the_factor_and_the_texture() {
    let dir = tempfile::tempdir().unwrap();
    let n = 6;
    // Float VEC3, as stored.
    let float: Vec<[f32; 3]> = (0..n).map(|i| [0.125 * i as f32, 1.0 - 0.125 * i as f32, 0.5]).collect();
    // Normalized unsigned byte VEC4: c / 255, alpha dropped, no sRGB decoding (§3.7.2.1: linear).
    let bytes: Vec<[u8; 4]> = (0..n).map(|i| [(40 * i) as u8, 128, 255 - (40 * i) as u8, 7]).collect();
    // Normalized unsigned short VEC3: c / 65535.
    let shorts: Vec<[u16; 3]> = (0..n).map(|i| [(10_000 * i) as u16, 65535, 32768]).collect();
    /// Name, bytes, component type, accessor type, the colours they stand for.
    type Encoding = (&'static str, Vec<u8>, u32, &'static str, Vec<[f64; 3]>);
    let encodings: [Encoding; 3] = [
        (
            "float VEC3",
            f32_bytes(&float.iter().flatten().copied().collect::<Vec<_>>()),
            FLOAT,
            "VEC3",
            float.iter().map(|c| c.map(f64::from)).collect(),
        ),
        (
            "u8 VEC4",
            bytes.iter().flatten().copied().collect(),
            UBYTE,
            "VEC4",
            bytes.iter().map(|c| [c[0], c[1], c[2]].map(|x| x as f64 / 255.0)).collect(),
        ),
        (
            "u16 VEC3",
            shorts.iter().flatten().flat_map(|x| x.to_le_bytes()).collect(),
            USHORT,
            "VEC3",
            shorts.iter().map(|c| c.map(|x| x as f64 / 65535.0)).collect(),
        ),
    ];
    for (name, data, component, ty, want) in &encodings {
        let mut a = Asset::default();
        a.primitive(n, &[], None);
        let colour = a.accessor(data, *component, n, ty, *component != FLOAT);
        a.primitives[0] =
            a.primitives[0].replace("\"POSITION\": 0", &format!("\"POSITION\": 0, \"COLOR_0\": {colour}"));
        let path = a.write_gltf(&dir.path().join("c.gltf"));
        let mesh = Mesh::load_coloured(&path).unwrap();
        // Exact: c / 255 and c / 65535 in f64, as the specification's formula gives them.
        assert_eq!(mesh.base_colors.as_ref().unwrap(), want, "{name}");
    }
    // 128 / 255 is read as it is, not decoded from sRGB (that would be 0.216).
    assert_eq!(encodings[1].4[0][1], 128.0 / 255.0);

    // baseColorFactor × COLOR_0 (u8) × the texture at texel centres.
    let uvs: Vec<[f64; 2]> = (0..n).map(|i| at((i % W) as f64, (i / W) as f64)).collect();
    let mut a = textured(&uvs, "", &png_uri(&png(W, W, code)), r#", "baseColorFactor": [0.5, 0.25, 0.75, 0.1]"#);
    let colour = a.accessor(&encodings[1].1, UBYTE, n, "VEC4", true);
    a.primitives[0] = a.primitives[0].replace("\"TEXCOORD_0\"", &format!("\"COLOR_0\": {colour}, \"TEXCOORD_0\""));
    let path = a.write_gltf(&dir.path().join("product.gltf"));
    let mesh = Mesh::load_coloured(&path).unwrap();
    let want: Vec<[f64; 3]> = (0..n)
        .map(|i| {
            let (t, c, f) = (texel(i % W, i / W), encodings[1].4[i], [0.5, 0.25, 0.75]);
            [0, 1, 2].map(|k| f[k] * c[k] * t[k])
        })
        .collect();
    assert_colours(mesh.base_colors.as_ref().unwrap(), &want, 1e-15, "factor × COLOR_0 × texture");
}

#[test]
fn primitives_without_material_are_white_and_the_texcoord_set_is_the_textures() {
    let dir = tempfile::tempdir().unwrap();
    let mut a = Asset::default();
    // Primitive 0: material 0 (a factor); primitive 1: no material; primitive 2: material 1,
    // its texture read at TEXCOORD_1 (TEXCOORD_0 points elsewhere).
    a.primitive(3, &[], Some(0));
    a.primitive(3, &[], None);
    let wrong = a.uvs(&[at(0.0, 0.0); 3]);
    let right = a.uvs(&[at(1.0, 2.0), at(3.0, 0.0), at(2.5, 1.0)]);
    a.primitive(3, &[("TEXCOORD_0", wrong), ("TEXCOORD_1", right)], Some(1));
    a.top = format!(
        r#", "materials": [{{"pbrMetallicRoughness": {{"baseColorFactor": [0.2, 0.4, 0.6, 1]}}}},
  {{"pbrMetallicRoughness": {{"baseColorTexture": {{"index": 0, "texCoord": 1}}}}}}],
 "textures": [{{"source": 0}}], "images": [{}]"#,
        png_uri(&png(W, W, code))
    );
    let path = a.write_gltf(&dir.path().join("three.gltf"));
    let mesh = Mesh::load_coloured(&path).unwrap();
    let f = [0.2f32, 0.4, 0.6].map(f64::from);
    let want = [f, f, f, [1.0; 3], [1.0; 3], [1.0; 3], texel(1, 2), texel(3, 0), mix(&[(2, 1, 0.5), (3, 1, 0.5)])];
    assert_colours(mesh.base_colors.as_ref().unwrap(), &want, 1e-12, "three primitives");
    assert_eq!(Mesh::load(&path).unwrap().positions, mesh.positions);

    // A hand-made scene placed by three nodes (testdata): white everywhere, in Mesh::load's order.
    let tetrahedra = Path::new(env!("CARGO_MANIFEST_DIR")).join("testdata/meshes/tetrahedra.gltf");
    let coloured = Mesh::load_coloured(&tetrahedra).unwrap();
    assert_eq!(coloured.positions, Mesh::load(&tetrahedra).unwrap().positions);
    assert_eq!(coloured.base_colors, Some(vec![[1.0; 3]; 12]));
}

#[test]
fn a_sixteen_bit_png_and_a_jpeg_are_decoded_too() {
    let dir = tempfile::tempdir().unwrap();
    // 16-bit: codes over 65535, then sRGB-decoded.
    let img =
        image::ImageBuffer::<image::Rgb<u16>, _>::from_fn(2, 1, |x, _| image::Rgb([1000 + 30000 * x as u16, 65535, 0]));
    let mut bytes = std::io::Cursor::new(Vec::new());
    img.write_to(&mut bytes, image::ImageFormat::Png).unwrap();
    let uvs = [[0.25, 0.5], [0.75, 0.5], [0.5, 0.5]];
    let path = textured(&uvs, "", &png_uri(&bytes.into_inner()), "").write_gltf(&dir.path().join("16.gltf"));
    let mesh = Mesh::load_coloured(&path).unwrap();
    let (a, b) = ([lin(1000, 65535), 1.0, 0.0], [lin(31000, 65535), 1.0, 0.0]);
    let want = [a, b, [0, 1, 2].map(|k| 0.5 * a[k] + 0.5 * b[k])];
    assert_colours(mesh.base_colors.as_ref().unwrap(), &want, 1e-12, "16-bit PNG");

    // A JPEG of one flat colour (lossy, so within 2 codes), as a file beside the asset.
    let flat = image::RgbImage::from_pixel(16, 16, image::Rgb([200, 100, 50]));
    let mut jpeg = std::io::Cursor::new(Vec::new());
    image::codecs::jpeg::JpegEncoder::new_with_quality(&mut jpeg, 100).encode_image(&flat).unwrap();
    std::fs::write(dir.path().join("flat.jpg"), jpeg.into_inner()).unwrap();
    let path = textured(&uvs, "", r#"{"uri": "flat.jpg"}"#, "").write_gltf(&dir.path().join("jpeg.gltf"));
    let mesh = Mesh::load_coloured(&path).unwrap();
    for c in mesh.base_colors.unwrap() {
        for (k, code) in [200u32, 100, 50].into_iter().enumerate() {
            assert!(c[k] >= lin(code - 2, 255) && c[k] <= lin(code + 2, 255), "{c:?}");
        }
    }
}

/// A PNG header claiming `width` × `height` (IHDR with its CRC, then an IDAT and IEND): enough
/// for a decoder to read the size, not to decode.
fn png_header(width: u32, height: u32) -> Vec<u8> {
    fn crc32(bytes: &[u8]) -> u32 {
        let mut crc = 0xFFFF_FFFFu32;
        for &b in bytes {
            crc ^= b as u32;
            for _ in 0..8 {
                crc = if crc & 1 != 0 { (crc >> 1) ^ 0xEDB8_8320 } else { crc >> 1 };
            }
        }
        !crc
    }
    let chunk = |kind: &[u8], data: &[u8]| {
        let mut c = (data.len() as u32).to_be_bytes().to_vec();
        let mut body = kind.to_vec();
        body.extend_from_slice(data);
        c.extend_from_slice(&body);
        c.extend(crc32(&body).to_be_bytes());
        c
    };
    let mut ihdr = width.to_be_bytes().to_vec();
    ihdr.extend(height.to_be_bytes());
    ihdr.extend([8, 2, 0, 0, 0]);
    let mut out = b"\x89PNG\r\n\x1a\n".to_vec();
    out.extend(chunk(b"IHDR", &ihdr));
    out.extend(chunk(b"IDAT", &[0x78, 0x9c, 0x03, 0x00]));
    out.extend(chunk(b"IEND", &[]));
    out
}

#[test]
fn textures_that_cannot_be_read_are_errors_naming_the_file_and_the_texture() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let uvs = [at(0.0, 0.0), at(1.0, 0.0), at(0.0, 1.0)];
    let good = png_uri(&png(W, W, code));
    let texture = "mesh 0, primitive 0, material 0, baseColorTexture (texture 0";
    let cases: Vec<(PathBuf, String, bool)> = vec![
        // A missing file: named, and plain `load` still reads the mesh.
        (
            textured(&uvs, "", r#"{"uri": "missing.png"}"#, "").write_gltf(&d.join("missing.gltf")),
            format!("{texture}, image 0): cannot read \"missing.png\": "),
            true,
        ),
        (
            textured(&uvs, "", r#"{"uri": "data:image/png;base64,aGVsbG8="}"#, "").write_gltf(&d.join("hello.gltf")),
            format!("{texture}, image 0): cannot decode the image: "),
            true,
        ),
        (
            textured(&uvs, "", &png_uri(&png_header(100_000, 100_000)), "").write_gltf(&d.join("huge.gltf")),
            format!("{texture}, image 0) (100000x100000) is 10000000000 texels, above the ceiling of 268435456 texels"),
            true,
        ),
        (
            textured(&uvs, "", &good, "").write_gltf(&d.join("set.gltf")),
            format!("{texture}): it is read at TEXCOORD_1, which the primitive lacks"),
            true,
        ),
        (
            textured(&uvs, "", &good, "").write_gltf(&d.join("transform.gltf")),
            format!("{texture}): KHR_texture_transform (an offset, rotation or scale of its UVs), which prtkit does not read"),
            true,
        ),
        (
            textured(&uvs, "", &good, r#", "baseColorFactor": [1, -0.5, 1, 1]"#).write_gltf(&d.join("factor.gltf")),
            "mesh 0, primitive 0, material 0: baseColorFactor [1.0, -0.5, 1.0] is not a colour".into(),
            true,
        ),
    ];
    // The two edits the cases above name: TEXCOORD_1, and a KHR_texture_transform.
    let edit = |name: &str, from: &str, to: &str| {
        let p = d.join(name);
        let text = std::fs::read_to_string(&p).unwrap();
        assert!(text.contains(from));
        std::fs::write(&p, text.replace(from, to)).unwrap();
    };
    edit("set.gltf", r#""index": 0}"#, r#""index": 0, "texCoord": 1}"#);
    edit(
        "transform.gltf",
        r#""index": 0}"#,
        r#""index": 0, "extensions": {"KHR_texture_transform": {"scale": [2, 2]}}}"#,
    );
    for (path, reason, loads) in cases {
        let name = path.display().to_string();
        let message = Mesh::load_coloured(&path).unwrap_err().to_string();
        assert!(message.starts_with(&format!("{name}: ")) && message.contains(&reason), "{name}: {message}");
        assert!(!message.contains("  "), "{name}: {message}");
        assert_eq!(Mesh::load(&path).is_ok(), loads, "{name}: Mesh::load");
    }
    // The missing image is named where it was looked for, beside the asset.
    let message = Mesh::load_coloured(&d.join("missing.gltf")).unwrap_err().to_string();
    assert!(message.contains(&d.join("missing.png").display().to_string()), "{message}");

    // A negative float COLOR_0.
    let mut a = Asset::default();
    a.primitive(3, &[], None);
    let colour = a.accessor(&f32_bytes(&[1.0, 1.0, 1.0, 0.5, -0.25, 0.5, 1.0, 1.0, 1.0]), FLOAT, 3, "VEC3", false);
    a.primitives[0] = a.primitives[0].replace("\"POSITION\": 0", &format!("\"POSITION\": 0, \"COLOR_0\": {colour}"));
    let path = a.write_gltf(&d.join("negative.gltf"));
    let message = Mesh::load_coloured(&path).unwrap_err().to_string();
    assert!(
        message.contains("negative.gltf: mesh 0, primitive 0: COLOR_0 of vertex 1 is [0.5, -0.25, 0.5]"),
        "{message}"
    );
}

// ---------------------------------------------------------------------------------------------
// PLY and OBJ
// ---------------------------------------------------------------------------------------------

const PLY_FACES: &str = "3 0 1 2\n3 0 2 3\n";

#[test]
fn ply_uchar_colours_are_srgb_and_float_colours_linear() {
    let dir = tempfile::tempdir().unwrap();
    // uchar with alpha, the colour between the coordinates: decoded from sRGB.
    let ascii = format!(
        "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty uchar red\nproperty uchar green\n\
         property float y\nproperty uchar blue\nproperty uchar alpha\nproperty float z\nelement face 2\n\
         property list uchar int vertex_indices\nend_header\n\
         0 255 0 0 128 9 0\n1 10 188 0 0 9 0\n1 64 64 1 64 9 0\n0 0 255 1 255 9 0.5\n{PLY_FACES}"
    );
    let path = dir.path().join("srgb.ply");
    std::fs::write(&path, ascii).unwrap();
    let mesh = Mesh::load_coloured(&path).unwrap();
    let l = |c: u32| lin(c, 255);
    let want = [[1.0, 0.0, l(128)], [l(10), l(188), 0.0], [l(64), l(64), l(64)], [0.0, 1.0, 1.0]];
    assert_colours(mesh.base_colors.as_ref().unwrap(), &want, 1e-15, "uchar");
    assert_eq!(mesh.positions, Mesh::load(&path).unwrap().positions);

    // float, binary little-endian: linear, as stored.
    let mut bin = b"ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
                   property float z\nproperty float red\nproperty float green\nproperty float blue\nelement face 2\n\
                   property list uchar int vertex_indices\nend_header\n"
        .to_vec();
    let colours = [[0.25f32, 0.5, 0.75], [1.0, 0.0, 0.125], [0.5, 0.5, 0.5], [0.0, 0.0, 2.0]];
    for (p, c) in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.5]].iter().zip(&colours) {
        bin.extend(f32_bytes(p));
        bin.extend(f32_bytes(c));
    }
    for face in [[0i32, 1, 2], [0, 2, 3]] {
        bin.push(3);
        bin.extend(face.iter().flat_map(|i| i.to_le_bytes()));
    }
    let path = dir.path().join("float.ply");
    std::fs::write(&path, &bin).unwrap();
    let mesh = Mesh::load_coloured(&path).unwrap();
    let want: Vec<[f64; 3]> = colours.iter().map(|c| c.map(f64::from)).collect();
    assert_eq!(mesh.base_colors.as_ref().unwrap(), &want);
    assert_eq!(mesh.positions, Mesh::load(&path).unwrap().positions);
}

#[test]
fn plys_without_usable_colours_and_objs_are_errors_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let header = |props: &str| {
        format!(
            "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n{props}\
             element face 2\nproperty list uchar int vertex_indices\nend_header\n"
        )
    };
    let rows = |extra: [&str; 4]| {
        let p = ["0 0 0", "1 0 0", "1 1 0", "0 1 0"];
        (0..4).map(|i| format!("{} {}\n", p[i], extra[i])).collect::<String>()
    };
    let colour = "property uchar red\nproperty uchar green\nproperty uchar blue\n";
    let cases = [
        ("none.ply", header(""), rows([""; 4]), "has no vertex colours (red, green, blue)"),
        (
            "ushort.ply",
            header(&colour.replace("uchar", "ushort")),
            rows(["1 2 3"; 4]),
            "the vertex colours (red, green, blue) are [\"ushort\", \"ushort\", \"ushort\"]",
        ),
        (
            "negative.ply",
            header(&colour.replace("uchar", "float")),
            rows(["1 1 1", "0.5 -1 0", "1 1 1", "1 1 1"]),
            "vertex 1's colour (red, green, blue) [0.5, -1.0, 0.0] is negative or not finite",
        ),
        (
            "nan.ply",
            header(&colour.replace("uchar", "double")),
            rows(["1 1 1", "1 1 1", "1 nan 1", "1 1 1"]),
            "vertex 2's colour",
        ),
        ("300.ply", header(colour), rows(["1 1 1", "1 1 1", "1 1 1", "300 1 1"]), "is not three uchar codes 0..255"),
    ];
    for (name, header, rows, reason) in cases {
        let path = dir.path().join(name);
        std::fs::write(&path, format!("{header}{rows}{PLY_FACES}")).unwrap();
        let message = Mesh::load_coloured(&path).unwrap_err().to_string();
        assert!(message.starts_with(&format!("{}: ", path.display())) && message.contains(reason), "{name}: {message}");
        assert!(!message.contains("  "), "{name}: {message}");
        let plain = Mesh::load(&path).unwrap();
        assert!(plain.base_colors.is_none() && plain.positions.len() == 4, "{name}");
    }

    let obj = Path::new(env!("CARGO_MANIFEST_DIR")).join("testdata/meshes/bowl.obj");
    let message = Mesh::load_coloured(&obj).unwrap_err().to_string();
    assert!(
        message.starts_with(&format!("{}: OBJ vertex colours are not read", obj.display())) && message.contains("glTF"),
        "{message}"
    );
    assert!(!message.contains("  "), "{message}");
    assert!(Mesh::load(&obj).is_ok());
}

#[test]
fn garbled_coloured_assets_are_errors_never_panics() {
    // A .glb with COLOR_0, a texture in a bufferView and a sampler, and a binary PLY with
    // colours, each with bytes overwritten at pseudo-random places (a fixed LCG): whatever
    // `load_coloured` makes of them, it returns.
    let dir = tempfile::tempdir().unwrap();
    let uvs = pad(vec![at(0.0, 0.0), at(5.0, -2.0), at(1.5, 2.25)]);
    let mut a =
        textured(&uvs, r#"{"wrapS": 33648, "wrapT": 33071}"#, r#"{"bufferView": 0, "mimeType": "image/png"}"#, "");
    let colour = a.accessor(&[200u8, 100, 50, 255].repeat(3), UBYTE, 3, "VEC4", true);
    a.primitives[0] = a.primitives[0].replace("\"TEXCOORD_0\"", &format!("\"COLOR_0\": {colour}, \"TEXCOORD_0\""));
    let view = a.view(&png(W, W, code));
    a.top = a.top.replace(r#""bufferView": 0, "mimeType""#, &format!(r#""bufferView": {view}, "mimeType""#));
    let glb = std::fs::read(a.write_glb(&dir.path().join("good.glb"))).unwrap();
    assert!(Mesh::load_coloured(&dir.path().join("good.glb")).is_ok());
    let mut ply = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
                    property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nelement face 1\n\
                    property list uchar int vertex_indices\nend_header\n"
        .to_vec();
    for p in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
        ply.extend(f32_bytes(&p));
        ply.extend([10, 20, 30]);
    }
    ply.push(3);
    ply.extend([0i32, 1, 2].iter().flat_map(|i| i.to_le_bytes()));
    std::fs::write(dir.path().join("good.ply"), &ply).unwrap();
    assert!(Mesh::load_coloured(&dir.path().join("good.ply")).is_ok());
    let mut state = 0x2545_F491_4F6C_DD1Du64;
    let mut next = move || {
        state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
        (state >> 33) as usize
    };
    let (mut ok, mut failed) = (0, 0);
    for (name, bytes) in [("m.glb", &glb), ("m.ply", &ply)] {
        for _ in 0..1500 {
            let mut garbled = bytes.clone();
            for _ in 0..1 + next() % 4 {
                let at = next() % garbled.len();
                garbled[at] = next() as u8;
            }
            let path = dir.path().join(name);
            std::fs::write(&path, &garbled).unwrap();
            match Mesh::load_coloured(&path) {
                Ok(mesh) => {
                    let colours = mesh.base_colors.unwrap();
                    assert_eq!(colours.len(), mesh.positions.len());
                    assert!(colours.iter().flatten().all(|c| c.is_finite() && *c >= 0.0));
                    ok += 1;
                }
                Err(e) => {
                    assert!(e.to_string().starts_with(&path.display().to_string()), "{e}");
                    failed += 1;
                }
            }
        }
    }
    // Both outcomes happen: the garbling reaches the parts that matter and the parts that do not.
    assert!(ok > 100 && failed > 100, "{ok} read, {failed} refused");
}
