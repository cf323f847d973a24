//! Compiles every shader in `glsl/` to SPIR-V with the `glslang` crate.
//!
//! Shaders `#include "camera_model.glsl"` (and friends) from `glsl/include/`; the include
//! handler below resolves those names. A compile error fails the build with the shader's path
//! and line, e.g. `glsl/points.comp:42: 'foo' : undeclared identifier`.
//!
//! The SPIR-V lands in `$OUT_DIR/<file name>.spv` (e.g. `points.comp.spv`) and is embedded
//! with `include_bytes!` by `src/gpu/shaders.rs`. A shader with a line
//! `// vklens:variant NAME DEFINE` is compiled once more with `#define DEFINE`, to
//! `<file name>.NAME.spv` (e.g. `points.comp.f64.spv`, the f64 model); `DEFINE` may be several,
//! comma-separated (`// vklens:variant forward_f64 VKL_F64,VKL_POINTS_FORWARD`).

use std::fs;
use std::path::{Path, PathBuf};

use glslang::include::{IncludeHandler, IncludeResult, IncludeType};
use glslang::{
    Compiler, CompilerOptions, ShaderInput, ShaderMessage, ShaderSource, ShaderStage, SpirvVersion,
    Target, VulkanVersion,
};

struct Includes {
    dir: PathBuf,
}

impl IncludeHandler for Includes {
    fn include(
        &mut self,
        _ty: IncludeType,
        header_name: &str,
        _includer_name: &str,
        _include_depth: usize,
    ) -> Option<IncludeResult> {
        let path = self.dir.join(header_name);
        let data = fs::read_to_string(&path).ok()?;
        Some(IncludeResult {
            name: format!("glsl/include/{header_name}"),
            data,
        })
    }
}

fn stage_of(path: &Path) -> Option<ShaderStage> {
    match path.extension()?.to_str()? {
        "comp" => Some(ShaderStage::Compute),
        "vert" => Some(ShaderStage::Vertex),
        "frag" => Some(ShaderStage::Fragment),
        "geom" => Some(ShaderStage::Geometry),
        _ => None,
    }
}

/// glslang reports the top-level file as string `0`; say which file that is.
fn locate(log: &str, shown: &str) -> String {
    log.replace("ERROR: 0:", &format!("ERROR: {shown}:"))
        .replace("WARNING: 0:", &format!("WARNING: {shown}:"))
}

fn main() {
    let root =
        PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR"));
    let out = PathBuf::from(std::env::var("OUT_DIR").expect("cargo sets OUT_DIR"));
    let glsl = root.join("glsl");
    println!("cargo:rerun-if-changed=glsl");

    let compiler = Compiler::acquire().expect("glslang failed to initialise");
    let options = CompilerOptions {
        target: Target::Vulkan {
            version: VulkanVersion::Vulkan1_1,
            spirv_version: SpirvVersion::SPIRV1_3,
        },
        messages: ShaderMessage::DEFAULT,
        ..CompilerOptions::default()
    };

    let mut entries: Vec<PathBuf> = fs::read_dir(&glsl)
        .expect("glsl/ exists")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| stage_of(p).is_some())
        .collect();
    entries.sort();
    for entry in fs::read_dir(glsl.join("include"))
        .into_iter()
        .flatten()
        .flatten()
    {
        println!("cargo:rerun-if-changed={}", entry.path().display());
    }

    let mut failures = Vec::new();
    for path in &entries {
        println!("cargo:rerun-if-changed={}", path.display());
        let name = path
            .file_name()
            .and_then(|n| n.to_str())
            .expect("utf-8 shader name");
        let shown = format!("glsl/{name}");
        let stage = stage_of(path).expect("filtered above");
        let text = fs::read_to_string(path).unwrap_or_else(|e| panic!("{shown}: {e}"));
        let mut variants: Vec<(String, Option<String>)> = vec![(format!("{name}.spv"), None)];
        for line in text.lines() {
            if let Some(rest) = line.trim().strip_prefix("// vklens:variant ") {
                let mut parts = rest.split_whitespace();
                if let (Some(suffix), Some(define)) = (parts.next(), parts.next()) {
                    variants.push((format!("{name}.{suffix}.spv"), Some(define.to_string())));
                }
            }
        }
        for (output, define) in variants {
            let source = ShaderSource::from(text.clone());
            let mut includes = Includes {
                dir: glsl.join("include"),
            };
            // A variant may set several defines, comma-separated.
            let defines: Vec<(&str, Option<&str>)> = define
                .iter()
                .flat_map(|d| d.split(','))
                .map(|d| (d, Some("1")))
                .collect();
            let input = match ShaderInput::new(
                &source,
                stage,
                &options,
                Some(&defines[..]),
                Some(&mut includes),
            ) {
                Ok(input) => input,
                Err(e) => {
                    failures.push(format!("{shown}: {}", locate(&e.to_string(), &shown)));
                    continue;
                }
            };
            let result = compiler
                .create_shader(input)
                .and_then(|shader| shader.compile());
            match result {
                Ok(words) => {
                    let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
                    fs::write(out.join(&output), bytes).expect("write SPIR-V");
                }
                Err(e) => failures.push(format!(
                    "{shown} ({}): {}",
                    define.as_deref().unwrap_or("default"),
                    locate(&e.to_string(), &shown)
                )),
            }
        }
    }
    if !failures.is_empty() {
        for f in &failures {
            eprintln!("{f}");
        }
        panic!(
            "{} shader(s) failed to compile:\n{}",
            failures.len(),
            failures.join("\n")
        );
    }
}
