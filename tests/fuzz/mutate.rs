//! Structure-aware mutators: generic byte mutations (bit flips, interesting values, insert,
//! delete, duplicate, truncate, splice) and per-format ones (EXR header attributes, Radiance
//! and PFM header numbers, MERL header and samples, JSON values, shading-language tokens, OBJ
//! and manifest lines, BRDF spec grammar). Each takes a seeded generator, so a run is
//! reproducible from its seed.

pub use prtkit::rng::SplitMix64 as Rng;

/// Integers that break size arithmetic: zero, one, sign and width boundaries, and sizes just
/// past prtkit's ceilings.
pub const INTERESTING_INTS: [i64; 16] = [
    0,
    1,
    -1,
    2,
    255,
    65_535,
    65_536,
    99_999,
    16_385,
    2001,
    i32::MAX as i64,
    i32::MIN as i64,
    u32::MAX as i64,
    1_000_000_000_000,
    i64::MAX,
    i64::MIN,
];

/// Numbers that break floating-point arithmetic.
pub const INTERESTING_NUMBERS: [&str; 16] = [
    "0",
    "-0",
    "1e308",
    "-1e308",
    "1e-308",
    "4.9e-324",
    "1e12",
    "4294967295",
    "18446744073709551615",
    "-1",
    "1e39",
    "nan",
    "inf",
    "6.3e8",
    "2.8e-5",
    "99999",
];

/// A random index below `n` (n > 0).
pub fn below(rng: &mut Rng, n: usize) -> usize {
    (rng.next_u64() % n.max(1) as u64) as usize
}

/// One of `items`.
pub fn pick<'a, T>(rng: &mut Rng, items: &'a [T]) -> &'a T {
    &items[below(rng, items.len())]
}

/// One generic byte mutation of `data` (`other` is a second input to splice from).
pub fn bytes(rng: &mut Rng, data: &[u8], other: &[u8]) -> Vec<u8> {
    let mut d = data.to_vec();
    if d.is_empty() {
        return other.to_vec();
    }
    let at = below(rng, d.len());
    match below(rng, 9) {
        0 => d[at] ^= 1 << below(rng, 8),
        1 => d[at] = *pick(rng, &[0u8, 0xff, 0x7f, 0x80, 1, b'\n', b'{', b'"']),
        2 => {
            let n = 1 + below(rng, 16);
            let fresh: Vec<u8> = (0..n).map(|_| rng.next_u64() as u8).collect();
            d.splice(at..at, fresh);
        }
        3 => {
            let end = (at + 1 + below(rng, 64)).min(d.len());
            d.drain(at..end);
        }
        4 => {
            let end = (at + 1 + below(rng, 256)).min(d.len());
            let copy = d[at..end].to_vec();
            let to = below(rng, d.len());
            d.splice(to..to, copy);
        }
        5 => d.truncate(at),
        6 if !other.is_empty() => {
            let from = below(rng, other.len());
            let end = (from + 1 + below(rng, 512)).min(other.len());
            let end_here = (at + below(rng, 512)).min(d.len());
            d.splice(at..end_here, other[from..end].iter().copied());
        }
        7 => {
            // An interesting 32-bit little-endian integer at a random offset.
            let v = (*pick(rng, &INTERESTING_INTS) as i32).to_le_bytes();
            let at = at.min(d.len().saturating_sub(4));
            for (k, b) in v.iter().enumerate() {
                if let Some(x) = d.get_mut(at + k) {
                    *x = *b;
                }
            }
        }
        _ => {
            // An interesting 64-bit float at a random offset.
            let v = pick(rng, &[f64::NAN, f64::INFINITY, -1.0, 1e308, 0.0]).to_le_bytes();
            let at = at.min(d.len().saturating_sub(8));
            for (k, b) in v.iter().enumerate() {
                if let Some(x) = d.get_mut(at + k) {
                    *x = *b;
                }
            }
        }
    }
    d
}

/// Offsets of the value of each EXR header attribute `name` of type `ty` (all parts).
fn exr_attribute(data: &[u8], name: &str, ty: &str) -> Vec<usize> {
    let key = format!("{name}\0{ty}\0");
    let mut out = Vec::new();
    let mut from = 0;
    while let Some(i) = data[from..].windows(key.len()).position(|w| w == key.as_bytes()) {
        let value = from + i + key.len() + 4; // after the i32 size
        out.push(value);
        from = from + i + 1;
    }
    out
}

fn put_i32(d: &mut [u8], at: usize, v: i32) {
    if let Some(s) = d.get_mut(at..at + 4) {
        s.copy_from_slice(&v.to_le_bytes());
    }
}

/// An EXR mutation: patch the data or display window, the chunk count, a channel's sample
/// type, the compression, or the offset table; else a generic byte mutation.
pub fn exr(rng: &mut Rng, data: &[u8], other: &[u8]) -> Vec<u8> {
    let mut d = data.to_vec();
    let int = |rng: &mut Rng| *pick(rng, &INTERESTING_INTS) as i32;
    match below(rng, 6) {
        0 | 1 => {
            let windows = exr_attribute(&d, "dataWindow", "box2i");
            if let Some(&at) = windows.get(below(rng, windows.len())) {
                if below(rng, 2) == 0 {
                    // The case: 0,0,99999,99999 (or another size), chunk count to match.
                    let side = int(rng);
                    for (k, v) in [0, 0, side, side].into_iter().enumerate() {
                        put_i32(&mut d, at + 4 * k, v);
                    }
                    let chunks = exr_attribute(&d, "chunkCount", "int");
                    if let Some(&c) = chunks.first() {
                        put_i32(&mut d, c, (side as i64 + 1).div_euclid(16).clamp(0, i32::MAX as i64) as i32);
                    }
                } else {
                    put_i32(&mut d, at + 4 * below(rng, 4), int(rng));
                }
            }
        }
        2 => {
            let chunks = exr_attribute(&d, "chunkCount", "int");
            if let Some(&c) = chunks.first() {
                put_i32(&mut d, c, int(rng));
            }
        }
        3 => {
            // chlist: name\0, then pixel type i32: set it to U32 (0), F16 (1), F32 (2) or junk.
            let lists = exr_attribute(&d, "channels", "chlist");
            if let Some(&at) = lists.first() {
                if let Some(nul) = d[at..].iter().position(|&b| b == 0) {
                    put_i32(&mut d, at + nul + 1, *pick(rng, &[0, 1, 2, 3, -1, 99]));
                }
            }
        }
        4 => {
            let comp = exr_attribute(&d, "compression", "compression");
            if let Some(&at) = comp.first() {
                if let Some(b) = d.get_mut(at) {
                    *b = below(rng, 12) as u8;
                }
            }
        }
        _ => return bytes(rng, data, other),
    }
    d
}

/// Replaces one number of `text`'s header (the first `lines` lines) by an interesting one.
pub fn header_number(rng: &mut Rng, data: &[u8], lines: usize, other: &[u8]) -> Vec<u8> {
    let end = data.iter().enumerate().filter(|(_, &b)| b == b'\n').nth(lines).map_or(data.len(), |(i, _)| i);
    let head = &data[..end];
    let spans: Vec<(usize, usize)> = {
        let mut v = Vec::new();
        let mut i = 0;
        while i < head.len() {
            if head[i].is_ascii_digit() || head[i] == b'-' {
                let s = i;
                while i < head.len() && (head[i].is_ascii_digit() || b".-eE+".contains(&head[i])) {
                    i += 1;
                }
                v.push((s, i));
            } else {
                i += 1;
            }
        }
        v
    };
    if spans.is_empty() || below(rng, 4) == 0 {
        return bytes(rng, data, other);
    }
    let (s, e) = *pick(rng, &spans);
    let mut d = data[..s].to_vec();
    d.extend_from_slice(pick(rng, &INTERESTING_NUMBERS).as_bytes());
    d.extend_from_slice(&data[e..]);
    d
}

/// A MERL mutation: header dimensions, a non-finite sample, a size change by a few bytes.
pub fn merl(rng: &mut Rng, data: &[u8]) -> Vec<u8> {
    let mut d = data.to_vec();
    match below(rng, 4) {
        0 => put_i32(&mut d, 4 * below(rng, 3), *pick(rng, &INTERESTING_INTS) as i32),
        1 => {
            let at = 12 + 8 * below(rng, (d.len().saturating_sub(12)) / 8);
            let v = pick(rng, &[f64::NAN, f64::INFINITY, -1.0, 1e308]).to_le_bytes();
            if let Some(s) = d.get_mut(at..at + 8) {
                s.copy_from_slice(&v);
            }
        }
        2 => d.truncate(d.len().saturating_sub(1 + below(rng, 16))),
        _ => d.extend((0..1 + below(rng, 16)).map(|_| rng.next_u64() as u8)),
    }
    d
}

/// A JSON value that breaks loaders: extreme numbers, wrong types, deep nesting.
fn interesting_json(rng: &mut Rng) -> serde_json::Value {
    use serde_json::json;
    match below(rng, 12) {
        0 => json!(4_294_967_295u64),
        1 => json!(u64::MAX),
        2 => json!(1_000_000_000_000u64),
        3 => json!(-1),
        4 => json!(0),
        5 => json!(1e308),
        6 => json!(-1e308),
        7 => json!("not a number"),
        8 => json!(null),
        9 => json!([]),
        10 => json!({}),
        _ => {
            let mut v = json!(1);
            for _ in 0..1 + below(rng, 300) {
                v = json!([v]);
            }
            v
        }
    }
}

/// Every path to a value in `v` (object keys and array indices).
fn paths(v: &serde_json::Value, prefix: &mut Vec<serde_json::Value>, out: &mut Vec<Vec<serde_json::Value>>) {
    out.push(prefix.clone());
    match v {
        serde_json::Value::Object(m) => {
            for (k, x) in m {
                prefix.push(serde_json::Value::String(k.clone()));
                paths(x, prefix, out);
                prefix.pop();
            }
        }
        serde_json::Value::Array(a) => {
            for (i, x) in a.iter().enumerate().take(8) {
                prefix.push(serde_json::Value::from(i));
                paths(x, prefix, out);
                prefix.pop();
            }
        }
        _ => {}
    }
}

fn at_path<'a>(v: &'a mut serde_json::Value, path: &[serde_json::Value]) -> Option<&'a mut serde_json::Value> {
    let mut cur = v;
    for p in path {
        cur = match p {
            serde_json::Value::String(k) => cur.get_mut(k.as_str())?,
            serde_json::Value::Number(n) => cur.get_mut(n.as_u64()? as usize)?,
            _ => return None,
        };
    }
    Some(cur)
}

/// A JSON mutation: replace a value, delete a key, repeat an array's elements; or, for text
/// that does not parse, a byte mutation.
pub fn json(rng: &mut Rng, data: &[u8], other: &[u8]) -> Vec<u8> {
    let Ok(mut v) = serde_json::from_slice::<serde_json::Value>(data) else {
        return bytes(rng, data, other);
    };
    if below(rng, 5) == 0 {
        return bytes(rng, data, other);
    }
    let mut all = Vec::new();
    paths(&v, &mut Vec::new(), &mut all);
    let path = pick(rng, &all).clone();
    let kind = below(rng, 4);
    if let Some(slot) = at_path(&mut v, &path) {
        match (kind, slot) {
            (1, serde_json::Value::Object(m)) if !m.is_empty() => {
                let key = m.keys().nth(below(rng, m.len())).cloned().unwrap_or_default();
                m.remove(&key);
            }
            (2, serde_json::Value::Array(a)) if !a.is_empty() => {
                let times = *pick(rng, &[2usize, 10, 1000]);
                let copy = a.clone();
                for _ in 1..times.min(100_000 / copy.len().max(1)) {
                    a.extend(copy.iter().cloned());
                }
            }
            (_, slot) => *slot = interesting_json(rng),
        }
    }
    serde_json::to_vec_pretty(&v).unwrap_or_default()
}

/// A GLB mutation: the JSON chunk mutated as JSON ([`json`]) and the container built again
/// around it with its lengths right; or a byte mutation (lengths and chunk headers wrong too).
pub fn glb(rng: &mut Rng, data: &[u8], other: &[u8]) -> Vec<u8> {
    let (Some(document), Some(bin)) = (prtkit::io::glb::json_chunk(data), prtkit::io::glb::bin_chunk(data)) else {
        return bytes(rng, data, other);
    };
    if below(rng, 4) == 0 {
        return bytes(rng, data, other);
    }
    let text = json(rng, &serde_json::to_vec(&document).unwrap_or_default(), &[]);
    glb_container(&text, bin)
}

/// A `.glb` of a JSON chunk and a BIN chunk (glTF 2.0 §4.4), each padded to 4 bytes.
pub fn glb_container(json: &[u8], bin: &[u8]) -> Vec<u8> {
    let (mut json, mut bin) = (json.to_vec(), bin.to_vec());
    json.resize(json.len().next_multiple_of(4), b' ');
    bin.resize(bin.len().next_multiple_of(4), 0);
    let mut out = b"glTF".to_vec();
    out.extend(2u32.to_le_bytes());
    out.extend(((28 + json.len() + bin.len()) as u32).to_le_bytes());
    out.extend((json.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(json);
    out.extend((bin.len() as u32).to_le_bytes());
    out.extend(b"BIN\0");
    out.extend(bin);
    out
}

/// Splits shader source into tokens (identifiers, numbers, single symbols) and the text between.
fn tokens(src: &str) -> Vec<(usize, usize)> {
    let b = src.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let c = b[i];
        let s = i;
        if c.is_ascii_alphanumeric() || c == b'_' || c == b'.' {
            while i < b.len() && (b[i].is_ascii_alphanumeric() || b[i] == b'_' || b[i] == b'.') {
                i += 1;
            }
            out.push((s, i));
        } else if !c.is_ascii_whitespace() {
            i += 1;
            out.push((s, i));
        } else {
            i += 1;
        }
    }
    out
}

const WORDS: [&str; 16] =
    ["u", "v", "P", "D", "Ci", "abs", "snoise", "fbm", "mix", "pow", "for", "if", "float", "color", "return", "f"];

/// A shading-language mutation on tokens: a number replaced by an extreme one, an identifier
/// by another name, a token deleted or repeated, an operand wrapped in deeply nested calls or
/// extended into a long sum, a recursive function added; or a byte mutation.
pub fn shader(rng: &mut Rng, data: &[u8], other: &[u8]) -> Vec<u8> {
    let Ok(src) = std::str::from_utf8(data) else { return bytes(rng, data, other) };
    let toks = tokens(src);
    if toks.is_empty() {
        return bytes(rng, data, other);
    }
    let (s, e) = *pick(rng, &toks);
    let tok = &src[s..e];
    let replace = |with: String| format!("{}{with}{}", &src[..s], &src[e..]).into_bytes();
    match below(rng, 9) {
        0 | 1 => replace(pick(rng, &INTERESTING_NUMBERS).to_string()),
        2 => replace(pick(rng, &WORDS).to_string()),
        3 => replace(String::new()),
        4 => replace(format!("{tok} {tok}")),
        5 => {
            let n = *pick(rng, &[10usize, 250, 260, 600, 2000]);
            let f = pick(rng, &["abs(", "-", "(", "sin(", "snoise("]);
            let close = if f.ends_with('(') { ")" } else { "" };
            replace(format!("{}{tok}{}", f.repeat(n), close.repeat(n)))
        }
        6 => {
            let n = *pick(rng, &[100usize, 255, 600]);
            replace(format!("{tok}{}", " + u".repeat(n)))
        }
        7 => {
            let rec = "float fz(float x) { float r = 1; if (x > 0) { r = fz(x - 1) + fz(x - 1); } return r; }\n";
            let mut out = rec.to_string() + src;
            if let Some(i) = out.rfind('}') {
                out.insert_str(i, " Ci += fz(30); ");
            }
            out.into_bytes()
        }
        _ => bytes(rng, data, other),
    }
}

/// A line-based mutation for OBJ and manifests: a line deleted, repeated or with one field
/// replaced by an extreme number or index; or a byte mutation.
pub fn lines(rng: &mut Rng, data: &[u8], other: &[u8]) -> Vec<u8> {
    let Ok(text) = std::str::from_utf8(data) else { return bytes(rng, data, other) };
    let mut ls: Vec<String> = text.lines().map(str::to_string).collect();
    if ls.is_empty() || below(rng, 5) == 0 {
        return bytes(rng, data, other);
    }
    let i = below(rng, ls.len());
    match below(rng, 4) {
        0 => {
            ls.remove(i);
        }
        1 => {
            let l = ls[i].clone();
            ls.insert(i, l);
        }
        _ => {
            let mut fields: Vec<String> = ls[i].split_whitespace().map(str::to_string).collect();
            if !fields.is_empty() {
                let k = below(rng, fields.len());
                fields[k] = if below(rng, 2) == 0 {
                    pick(rng, &INTERESTING_NUMBERS).to_string()
                } else {
                    pick(rng, &INTERESTING_INTS).to_string()
                };
                ls[i] = fields.join(" ");
            }
        }
    }
    let mut out = ls.join("\n");
    out.push('\n');
    out.into_bytes()
}

/// A BRDF spec from the grammar with random (often extreme) parameters, or a byte mutation
/// of `data`.
pub fn brdf_spec(rng: &mut Rng, data: &[u8], other: &[u8]) -> Vec<u8> {
    if below(rng, 4) == 0 {
        return bytes(rng, data, other);
    }
    let num = |rng: &mut Rng| -> String {
        if below(rng, 2) == 0 {
            pick(rng, &INTERESTING_NUMBERS).to_string()
        } else {
            format!("{}", (rng.next_f64() * 100.0 * 10f64.powi(below(rng, 6) as i32 - 3)))
        }
    };
    let spec = match below(rng, 7) {
        0 => format!("lambert:albedo={}", num(rng)),
        1 => format!("phong:s={}", num(rng)),
        2 => format!("blinn-phong:s={}", num(rng)),
        3 => format!("torrance-sparrow:sigma={}", num(rng)),
        4 => format!("kajiya-kay:s={}", num(rng)),
        5 => format!("lafortune:kd={},lobe={}/{}/{}", num(rng), num(rng), num(rng), num(rng)),
        _ => format!("lafortune:lobe={}/{}/{}/{}", num(rng), num(rng), num(rng), num(rng)),
    };
    spec.into_bytes()
}

/// A KTX 2.0 file: a header field (format, sizes, counts, descriptor offsets) or a level-index
/// entry (offset, lengths) set to an interesting number, or a byte-level mutation.
pub fn ktx2(rng: &mut Rng, data: &[u8], other: &[u8]) -> Vec<u8> {
    let mut d = data.to_vec();
    let int = |rng: &mut Rng| *pick(rng, &INTERESTING_INTS);
    match below(rng, 3) {
        // vkFormat … kvdByteLength: twelve u32 fields from byte 12.
        0 => put_i32(&mut d, 12 + 4 * below(rng, 12), int(rng) as i32),
        1 => {
            let levels =
                d.get(40..44).map_or(1, |b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize).clamp(1, 16);
            let at = 80 + 8 * below(rng, 3 * levels);
            // Offsets into the header, the index, or past the end, besides the interesting ints.
            let v = match below(rng, 2) {
                0 => *pick(rng, &[0u64, 16, 80, 104, data.len() as u64, u64::MAX]),
                _ => int(rng) as u64,
            };
            if let Some(slot) = d.get_mut(at..at + 8) {
                slot.copy_from_slice(&v.to_le_bytes());
            }
        }
        _ => return bytes(rng, data, other),
    }
    d
}
