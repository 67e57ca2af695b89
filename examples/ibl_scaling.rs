//! How `ibl` scales: input lat-long maps from 512 × 256 to 16384 × 8192 at the default 256² faces,
//! and faces from 128² to 4096² on a 2048 × 1024 input, each run with the default measurement
//! and with `--samples 0`, timed (wall, CPU, peak resident memory: `/usr/bin/time`), Filament's
//! `cmgen --ibl-ld` beside it at the sizes it shares (Filament's roughness mapping and levels down
//! to 16², as `examples/peers.rs` runs both). The largest inputs also run under a 4 GiB address
//! space (`ulimit -v 4194304`), where `ibl` must complete or refuse up front. Writes Markdown
//! (scripts/ibl-scaling.sh writes docs/results/ibl-scaling.md).
//!
//! `cargo run --release --example ibl_scaling -- IBL CMGEN|- MAP WORKDIR OUT.md [--small]`
//!
//! The inputs are MAP resampled (bilinear) to each size and written as ZIP-compressed EXR.

use prtkit::envmap::{resample, Layout, LoadOptions};
use prtkit::ibl::manifest::{IblBody, FORMAT, VERSION};
use prtkit::io::document::read_document;
use prtkit::io::exr;
use std::fmt::Write;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

fn fail(message: &str) -> ! {
    eprintln!("ibl_scaling: {message}");
    std::process::exit(2);
}

/// One run: exit status, seconds of wall and CPU (user + system), peak resident MB, and the last
/// line the program wrote on stderr.
struct Run {
    ok: bool,
    code: Option<i32>,
    wall: f64,
    cpu: f64,
    rss_mb: f64,
    said: String,
}

/// Runs `program args` under `/usr/bin/time` (and `ulimit -v KB` when given), in a shell so the
/// limit applies to the program alone. The wall time is this process's clock around the run, not
/// `/usr/bin/time`'s `%e`, whose 10 ms steps are too coarse for the ratio of two sub-second bakes
/// (the shell and `time` add the same few milliseconds to both runs).
fn timed(program: &Path, args: &[String], limit_kb: Option<u64>) -> Run {
    let mut line = String::new();
    if let Some(kb) = limit_kb {
        let _ = write!(line, "ulimit -v {kb}; ");
    }
    let quoted: Vec<String> = std::iter::once(program.display().to_string())
        .chain(args.iter().cloned())
        .map(|a| format!("'{}'", a.replace('\'', r"'\''")))
        .collect();
    let _ = write!(line, "exec /usr/bin/time -f 'TIME %U %S %M' {}", quoted.join(" "));
    let start = Instant::now();
    let out = Command::new("bash").arg("-c").arg(&line).output().unwrap_or_else(|e| fail(&format!("bash: {e}")));
    let wall = start.elapsed().as_secs_f64();
    let stderr = String::from_utf8_lossy(&out.stderr);
    let times: Vec<f64> = stderr
        .lines()
        .rev()
        .find_map(|l| l.strip_prefix("TIME "))
        .map(|t| t.split_whitespace().filter_map(|v| v.parse().ok()).collect())
        .unwrap_or_default();
    if times.len() != 3 {
        fail(&format!("no timing from /usr/bin/time for {line}:\n{stderr}"));
    }
    // The program's last line, not /usr/bin/time's own ("Command exited with non-zero status").
    let said = stderr
        .lines()
        .rev()
        .find(|l| !l.starts_with("TIME ") && !l.starts_with("Command ") && !l.trim().is_empty())
        .unwrap_or("")
        .to_string();
    Run {
        ok: out.status.success(),
        code: out.status.code(),
        wall,
        cpu: times[0] + times[1],
        rss_mb: times[2] / 1024.0,
        said,
    }
}

/// The median of each figure over `runs` (the first run that failed, if one did).
fn median(mut runs: Vec<Run>) -> Run {
    if let Some(failed) = runs.iter().position(|r| !r.ok) {
        return runs.swap_remove(failed);
    }
    let of = |figure: fn(&Run) -> f64| {
        let mut v: Vec<f64> = runs.iter().map(figure).collect();
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let (wall, cpu, rss_mb) = (of(|r| r.wall), of(|r| r.cpu), of(|r| r.rss_mb));
    Run { wall, cpu, rss_mb, ..runs.swap_remove(0) }
}

/// Times each bake is run, alternating with the other, by the default run's wall seconds: a
/// run's ratio moves with whatever else the shared machine is doing, the more so the shorter it
/// is (and the largest inputs' runs, paging in gigabytes, move by a second or two).
fn repeats(wall: f64) -> usize {
    if wall < 3.0 {
        9
    } else if wall < 10.0 {
        3
    } else {
        1
    }
}

/// What the default run's manifest states its reference may be off by: the largest
/// `reference_bound` of its levels (relative, like the errors); none when the input was summed
/// texel by texel.
fn stated_bound(manifest: &Path) -> String {
    let body = read_document::<IblBody>(manifest, FORMAT, VERSION).unwrap_or_else(|e| fail(&e.to_string())).body;
    let levels = body.specular.levels.iter().chain([&body.irradiance.level]);
    match levels.filter_map(|l| l.reference_bound).reduce(f64::max) {
        Some(bound) => format!("{:.3} %", 100.0 * bound),
        None => "— (texel by texel)".into(),
    }
}

/// The input MAP at `width` × `height`, written once into `work`.
fn input(map: &prtkit::envmap::EnvMap, width: usize, work: &Path) -> PathBuf {
    let path = work.join(format!("map-{width}x{}.exr", width / 2));
    if !path.exists() {
        let resized = resample(map, Layout::LatLong, width, width / 2, 1).unwrap_or_else(|e| fail(&e.to_string()));
        exr::write_rgb(&path, resized.image()).unwrap_or_else(|e| fail(&e.to_string()));
    }
    path
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 6 {
        fail("usage: ibl_scaling IBL CMGEN|- MAP WORKDIR OUT.md [--small]");
    }
    let (ibl, map_path, work, out) =
        (PathBuf::from(&args[1]), PathBuf::from(&args[3]), PathBuf::from(&args[4]), &args[5]);
    let cmgen = (args[2] != "-").then(|| PathBuf::from(&args[2]));
    let small = args.iter().any(|a| a == "--small");
    let map = LoadOptions::default().load(&map_path).unwrap_or_else(|e| fail(&e.to_string())).map;

    // (input width, faces): the inputs at the default faces, then the faces on one input.
    let (widths, faces, faces_input, limited): (Vec<usize>, Vec<usize>, usize, Vec<usize>) = if small {
        (vec![128, 256], vec![16, 32], 256, vec![256])
    } else {
        (vec![512, 1024, 2048, 4096, 8192, 16384], vec![128, 256, 512, 1024, 2048, 4096], 2048, vec![8192, 16384])
    };
    let default_faces = if small { 32 } else { 256 };
    let cmgen_max_faces = if small { 32 } else { 512 };
    let mut cases: Vec<(usize, usize)> = widths.iter().map(|&w| (w, default_faces)).collect();
    cases.extend(faces.iter().filter(|&&f| f != default_faces).map(|&f| (faces_input, f)));

    let mut md = String::from(
        "## `ibl` at every scale\n\n\
         `scripts/ibl-scaling.sh` (`examples/ibl_scaling.rs`): `grace_latlong.exr` resampled to each input size; \
         `ibl IN -o DIR --size F --min-size 16 --roughness-map filament` (cmgen's levels and roughnesses) with \
         the default measurement (64 texels per level) and with `--samples 0`; `cmgen --format=exr --size=F \
         --ibl-ld=DIR IN` beside it where it finishes in reasonable time (faces up to 512²). Timed side by side \
         by `/usr/bin/time`: CPU (user + system) seconds and peak resident memory, and wall seconds by the \
         script's clock around each run; the two `ibl` \
         runs alternate nine times and each figure is their median where the default run takes under 3 s, \
         three times under 10 s (a run's ratio moves with whatever else the shared machine does), one run \
         of each otherwise, and one cmgen run. The machine has 2 cores. The stated bound is the largest \
         `reference_bound` in the default run's `ibl.json`: how far its reference may be from the texel-by-texel \
         sum over the input, relative like the errors (inputs above 4096 × 2048 are measured on their box \
         filtering, and the bound includes what that changes).\n\n\
         | input | faces | ibl wall s | ibl CPU s | ibl MB | stated bound | `--samples 0` wall s | CPU s | MB | default / `--samples 0` (wall) | cmgen wall s | cmgen CPU s | cmgen MB | cmgen / ibl default (CPU) |\n\
         | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n",
    );
    for &(width, face) in &cases {
        let path = input(&map, width, &work);
        let dir = work.join("bake");
        let bake = |samples: Option<&str>| -> Run {
            let _ = std::fs::remove_dir_all(&dir);
            let mut a = vec![path.display().to_string(), "-o".into(), dir.display().to_string()];
            a.extend(
                ["--size", &face.to_string(), "--min-size", "16", "--roughness-map", "filament", "-q"]
                    .map(String::from),
            );
            if let Some(s) = samples {
                a.extend(["--samples".to_string(), s.to_string()]);
            }
            timed(&ibl, &a, None)
        };
        let first = bake(None);
        let bound = stated_bound(&dir.join("ibl.json"));
        let (mut measured, mut plain) = (vec![first], vec![bake(Some("0"))]);
        if measured[0].ok && plain[0].ok {
            // Alternating, so that both see the same spells of load.
            for _ in 1..repeats(measured[0].wall) {
                measured.push(bake(None));
                plain.push(bake(Some("0")));
            }
        }
        let (measured, plain) = (median(measured), median(plain));
        if !measured.ok || !plain.ok {
            let _ = writeln!(
                md,
                "| {width} × {} | {face}² | failed: {} | | | | | | | | | | | |",
                width / 2,
                if measured.ok { &plain.said } else { &measured.said }
            );
            continue;
        }
        let peer = match &cmgen {
            Some(cmgen) if face <= cmgen_max_faces => {
                let cm_dir = work.join("cmgen");
                let _ = std::fs::remove_dir_all(&cm_dir);
                let a = vec![
                    "--format=exr".into(),
                    format!("--size={face}"),
                    format!("--ibl-ld={}", cm_dir.display()),
                    path.display().to_string(),
                ];
                let r = timed(cmgen, &a, None);
                if r.ok {
                    format!("{:.2} | {:.2} | {:.0} | {:.1}×", r.wall, r.cpu, r.rss_mb, r.cpu / measured.cpu.max(1e-9))
                } else {
                    format!("failed: {} | | |", r.said)
                }
            }
            _ => "— | — | — | —".into(),
        };
        let _ = writeln!(
            md,
            "| {width} × {} | {face}² | {:.2} | {:.2} | {:.0} | {bound} | {:.2} | {:.2} | {:.0} | {:.2} | {peer} |",
            width / 2,
            measured.wall,
            measured.cpu,
            measured.rss_mb,
            plain.wall,
            plain.cpu,
            plain.rss_mb,
            measured.wall / plain.wall.max(1e-9),
        );
        eprintln!(
            "ibl_scaling: {width}x{} at {face}²: {:.2} s measured, {:.2} s without",
            width / 2,
            measured.wall,
            plain.wall
        );
    }

    md.push_str(
        "\nUnder a 4 GiB address space (`ulimit -v 4194304`), the default run at 256² faces:\n\n\
         | input | exit | wall s | peak MB | what `ibl` said |\n| ---: | ---: | ---: | ---: | --- |\n",
    );
    for &width in &limited {
        let path = input(&map, width, &work);
        let dir = work.join("bake");
        let _ = std::fs::remove_dir_all(&dir);
        let a = vec![path.display().to_string(), "-o".into(), dir.display().to_string(), "-q".into()];
        let r = timed(&ibl, &a, Some(4_194_304));
        // The temporary directory's name says nothing: the input is named by its size.
        let said = if r.ok {
            "completed".to_string()
        } else {
            r.said.replace(&format!("{}/", work.display()), "").replace('|', "\\|")
        };
        let _ = writeln!(
            md,
            "| {width} × {} | {} | {:.2} | {:.0} | {said} |",
            width / 2,
            r.code.map_or("signal".to_string(), |c| c.to_string()),
            r.wall,
            r.rss_mb
        );
    }
    if let Err(e) = std::fs::write(out, md) {
        fail(&format!("{out}: {e}"));
    }
}
