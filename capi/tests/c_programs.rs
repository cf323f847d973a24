//! The C API from C and C++: the example host engine (`examples/c/embed.c`), the bad-input
//! suite (`tests/c/api_test.c`), the points functions and scene rendering (`tests/c/scene.c`)
//! bit for bit against the Rust library, the C++ program, and the bad-input suite under
//! valgrind. Each program is built here with
//! the system compiler against `include/vklens.h` and `libvklens.so`, using the flags
//! `vklens.pc` gives (so the pkg-config file is tested too). GPU programs run with the
//! Khronos validation layer on; any message fails them.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use vklens_core::{Camera, Device, InverseMethod, Pixels, Raster, SceneRenderer};

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("capi/ sits in the repository")
        .to_path_buf()
}

/// `target/<profile>`: where cargo put `libvklens.so`, `vklens.pc` and this test.
fn lib_dir() -> PathBuf {
    let exe = std::env::current_exe().expect("the test's own path");
    let dir = exe
        .parent()
        .and_then(Path::parent)
        .expect("target/<profile>/deps/<test>")
        .to_path_buf();
    assert!(
        dir.join("libvklens.so").exists(),
        "{}: libvklens.so missing; build it first: cargo build --release -p vklens-capi (scripts/test does)",
        dir.display()
    );
    dir
}

fn shared() -> PathBuf {
    std::env::var_os("VKLENS_SHARED")
        .map(PathBuf::from)
        .unwrap_or_else(|| repo().join("..").join("shared"))
}

/// `pkg-config --cflags --libs vklens` for this checkout's `vklens.pc`.
fn pkg_config_flags() -> Vec<String> {
    let out = Command::new("pkg-config")
        .args(["--cflags", "--libs", "vklens"])
        .env("PKG_CONFIG_PATH", lib_dir())
        .output()
        .expect("pkg-config runs (apt-get install pkg-config)");
    assert!(
        out.status.success(),
        "pkg-config: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let flags: Vec<String> = String::from_utf8_lossy(&out.stdout)
        .split_whitespace()
        .map(String::from)
        .collect();
    assert!(flags.iter().any(|f| f == "-lvklens"), "{flags:?}");
    assert!(
        flags
            .iter()
            .any(|f| f.starts_with("-I") && f.ends_with("include")),
        "{flags:?}"
    );
    flags
}

/// Builds `source` (C11, or C++17 for `.cpp`) with warnings as errors into a temporary folder.
fn build(source: &str, dir: &Path) -> PathBuf {
    let src = repo().join(source);
    let cpp = source.ends_with(".cpp");
    let compiler = if cpp {
        std::env::var("CXX").unwrap_or_else(|_| "c++".into())
    } else {
        std::env::var("CC").unwrap_or_else(|_| "cc".into())
    };
    let exe = dir.join(src.file_stem().expect("a file name"));
    let out = Command::new(&compiler)
        .arg(if cpp { "-std=c++17" } else { "-std=c11" })
        .args(["-Wall", "-Wextra", "-Werror", "-g"])
        .arg(&src)
        .args(pkg_config_flags())
        .args(["-lvulkan", "-lm"])
        .arg(format!("-Wl,-rpath,{}", lib_dir().display()))
        .arg("-o")
        .arg(&exe)
        .output()
        .unwrap_or_else(|e| panic!("{compiler}: {e}"));
    assert!(
        out.status.success(),
        "{compiler} {source}:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    exe
}

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("vklens-capi-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("a temporary folder");
    dir
}

/// A binary PPM (P6) or PGM (P5): width, height and the samples.
fn read_pnm(path: &Path) -> (u32, u32, Vec<u8>) {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut fields = Vec::new();
    let mut i = 0;
    while fields.len() < 4 {
        while bytes[i].is_ascii_whitespace() {
            i += 1;
        }
        let start = i;
        while !bytes[i].is_ascii_whitespace() {
            i += 1;
        }
        fields.push(String::from_utf8_lossy(&bytes[start..i]).to_string());
    }
    let (w, h) = (fields[1].parse().unwrap(), fields[2].parse().unwrap());
    (w, h, bytes[i + 1..].to_vec())
}

#[test]
fn the_c_host_engine_warps_as_vklens_distort_does() {
    let dir = temp("embed");
    let exe = build("examples/c/embed.c", &dir);
    let camera = repo().join("examples/cameras/prism_tilt.json");
    let run = Command::new(&exe)
        .arg(&camera)
        .arg(&dir)
        .env("VKLENS_VALIDATION", "1")
        .output()
        .expect("embed runs");
    assert!(
        run.status.success(),
        "embed exited {:?}:\n{}",
        run.status.code(),
        String::from_utf8_lossy(&run.stderr)
    );
    // The engine's own source image, as the GPU held it, through the command line.
    let (w, h, rgb) = read_pnm(&dir.join("source.ppm"));
    let source = Raster {
        width: w,
        height: h,
        pixels: vklens_core::Pixels::Rgba8(
            rgb.chunks_exact(3)
                .map(|p| [p[0], p[1], p[2], 255])
                .collect(),
        ),
        bit_depth: vklens_core::BitDepth::U8,
    };
    source.save(dir.join("source.png")).expect("source.png");
    let cli = lib_dir().join("vklens");
    assert!(
        cli.exists(),
        "{}: build it first (cargo build --release)",
        cli.display()
    );
    let status = Command::new(&cli)
        .arg("distort")
        .arg("--camera")
        .arg(&camera)
        .arg("--input")
        .arg(dir.join("source.png"))
        .arg("--output")
        .arg(dir.join("cli.png"))
        .arg("--mask")
        .arg(dir.join("cli-mask.png"))
        .stdout(Stdio::null())
        .status()
        .expect("vklens distort runs");
    assert!(status.success());
    let reference = Raster::load(dir.join("cli.png")).expect("cli.png");
    let (lw, lh, lens) = read_pnm(&dir.join("lens.ppm"));
    assert_eq!((lw, lh), (reference.width, reference.height));
    let mut worst = 0;
    for i in 0..reference.len() {
        let r = reference.rgba_f32(i);
        for c in 0..3 {
            let want = (r[c] * 255.0).round() as i32;
            worst = worst.max((lens[3 * i + c] as i32 - want).abs());
        }
    }
    assert!(
        worst <= 1,
        "the C host's lens image is {worst} grey levels off"
    );
    let (_, _, mask) = read_pnm(&dir.join("mask.pgm"));
    let cli_mask = Raster::load(dir.join("cli-mask.png")).expect("cli-mask.png");
    let differ = (0..cli_mask.len())
        .filter(|&i| (mask[i] > 127) != (cli_mask.rgba_f32(i)[0] > 0.5))
        .count();
    assert_eq!(differ, 0, "{differ} mask pixels differ");
    assert!(mask.contains(&0) && mask.contains(&255));
}

#[test]
fn bad_input_through_the_c_api_is_an_error_naming_the_argument() {
    let dir = temp("api");
    let exe = build("capi/tests/c/api_test.c", &dir);
    let run = Command::new(&exe)
        .env("VKLENS_VALIDATION", "1")
        .output()
        .expect("api_test runs");
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(
        run.status.success() && stdout.contains(" passed, 0 failed"),
        "{stdout}\n{}",
        String::from_utf8_lossy(&run.stderr)
    );
}

#[test]
fn the_c_api_under_valgrind_leaks_nothing_and_reads_nothing_invalid() {
    if Command::new("valgrind").arg("--version").output().is_err() {
        eprintln!("valgrind is not installed: skipped (apt-get install valgrind)");
        return;
    }
    let dir = temp("valgrind");
    let exe = build("capi/tests/c/api_test.c", &dir);
    // The calls that need no Vulkan: the driver's own allocations are not this library's.
    let run = Command::new("valgrind")
        .args([
            "--error-exitcode=9",
            "--leak-check=full",
            "--errors-for-leak-kinds=definite,indirect",
            "--quiet",
        ])
        .arg(&exe)
        .arg("--no-gpu")
        .output()
        .expect("valgrind runs");
    assert!(
        run.status.success(),
        "valgrind exited {:?}:\n{}",
        run.status.code(),
        String::from_utf8_lossy(&run.stderr)
    );
}

#[test]
fn the_points_functions_equal_the_rust_library_bit_for_bit() {
    let dir = temp("points");
    let exe = build("capi/tests/c/points.c", &dir);
    let path = shared().join("reference/opencv_standard_model.json");
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let reference: serde_json::Value = serde_json::from_str(&text).expect("reference JSON");
    let cases = reference["cases"].as_array().expect("cases");
    let mut invalid = 0;
    for case in cases {
        let f = |k: &str| case[k].as_f64().expect("a number");
        let d: Vec<f64> = case["dist_coeffs"]
            .as_array()
            .expect("dist_coeffs")
            .iter()
            .map(|v| v.as_f64().expect("a number"))
            .collect();
        let k = [
            [f("fx"), 0.0, f("cx")],
            [0.0, f("fy"), f("cy")],
            [0.0, 0.0, 1.0],
        ];
        let size = (f("width") as u32, f("height") as u32);
        let camera = Camera::from_opencv(k, &d, size).expect("reference camera");
        let file = dir.join("camera.json");
        camera.save(&file).expect("camera.json");
        let points = case["points"].as_array().expect("points");
        let pick = |key: &str| -> Vec<[f64; 2]> {
            let mut v: Vec<[f64; 2]> = points
                .iter()
                .map(|p| [p[key][0].as_f64().unwrap(), p[key][1].as_f64().unwrap()])
                .collect();
            // and the hostile: non-finite, huge, far outside the domain
            v.extend([
                [f64::NAN, 0.0],
                [f64::INFINITY, 1.0],
                [1e300, -1e300],
                [1e6, 1e6],
            ]);
            v
        };
        for (mode, input) in [
            ("distort", pick("undistorted_normalized")),
            ("undistort", pick("distorted_pixel")),
        ] {
            let rust = match mode {
                "distort" => camera.distort_points(&input),
                _ => camera.undistort_points(&input, InverseMethod::Newton),
            };
            let c = run_points(&exe, &file, mode, &input);
            for (i, (r, c)) in rust.iter().zip(&c).enumerate() {
                match r {
                    Some(r) => assert!(
                        r[0].to_bits() == c[0].to_bits() && r[1].to_bits() == c[1].to_bits(),
                        "{} {mode} point {i}: Rust {r:?}, C {c:?}",
                        case["name"]
                    ),
                    None => {
                        assert!(c[0].is_nan() && c[1].is_nan(), "{mode} point {i}: {c:?}");
                        invalid += 1;
                    }
                }
            }
        }
    }
    assert!(
        invalid > 0,
        "the hostile points must hit the invalid branch"
    );
}

fn run_points(exe: &Path, camera: &Path, mode: &str, input: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let mut child = Command::new(exe)
        .arg(camera)
        .arg(mode)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .expect("points runs");
    let bytes: Vec<u8> = input
        .iter()
        .flatten()
        .flat_map(|v| v.to_ne_bytes())
        .collect();
    child
        .stdin
        .take()
        .expect("stdin")
        .write_all(&bytes)
        .expect("write points");
    let out = child.wait_with_output().expect("points finishes");
    assert!(out.status.success(), "points {mode} failed");
    out.stdout
        .chunks_exact(16)
        .map(|c| {
            let v = |b: &[u8]| f64::from_ne_bytes(b.try_into().expect("8 bytes"));
            [v(&c[..8]), v(&c[8..])]
        })
        .collect()
}

#[test]
fn a_cpp_program_includes_the_header_and_calls_the_camera_functions() {
    let dir = temp("cpp");
    let exe = build("examples/cpp/cameras.cpp", &dir);
    let run = Command::new(&exe)
        .arg(repo().join("examples/cameras/prism_tilt.json"))
        .output()
        .expect("cameras runs");
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(run.status.success(), "{stdout}");
    assert!(
        stdout.contains("800x600 camera; round trip within") && stdout.contains("missing file:")
    );
}

#[test]
fn a_c_program_renders_scene_files_as_the_rust_library_does() {
    let dir = temp("scene");
    let exe = build("capi/tests/c/scene.c", &dir);
    let run = Command::new(&exe)
        .arg(repo())
        .arg(&dir)
        .env("VKLENS_VALIDATION", "1")
        .output()
        .expect("scene runs");
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(
        run.status.success() && stdout.contains(" passed, 0 failed"),
        "{stdout}\n{}",
        String::from_utf8_lossy(&run.stderr)
    );
    // The same frame through SceneRenderer: the C frame's bytes are the Rust frame's.
    let scene = SceneRenderer::load(repo().join("examples/scenes/rolling_shutter.toml"))
        .expect("rolling_shutter.toml");
    let device = Device::new().expect("a device");
    let mut frames = Vec::new();
    scene
        .render(&device, 0..1, &mut |f| {
            frames.push(f);
            Ok(())
        })
        .expect("the Rust render");
    let r = &frames[0].rendered;
    let color: Vec<u8> = match &r.color.as_ref().expect("colour").pixels {
        Pixels::Rgba8(p) => p.iter().flatten().copied().collect(),
        other => panic!("colour as {other:?}: expected RGBA8"),
    };
    let ids: Vec<u8> = r
        .ids
        .as_ref()
        .expect("ids")
        .iter()
        .flat_map(|v| v.to_ne_bytes())
        .collect();
    let depth: Vec<u8> = r
        .depth
        .as_ref()
        .expect("depth")
        .iter()
        .flat_map(|v| v.to_ne_bytes())
        .collect();
    for (name, rust) in [("color", color), ("ids", ids), ("depth", depth)] {
        let c = std::fs::read(dir.join(format!("{name}.bin"))).expect("the C program's output");
        assert_eq!(c.len(), rust.len(), "{name}: sizes differ");
        let differ = c.iter().zip(&rust).filter(|(a, b)| a != b).count();
        assert_eq!(
            differ, 0,
            "{name}: {differ} bytes differ between C and Rust"
        );
    }
}
