//! Outputs are written safely: never half-written, never mixed by concurrent writers
//! (`cli/tests/it/outputs.rs` runs the commands on symlinks, devices, folders and one file named twice).

use std::path::{Path, PathBuf};

use super::write_atomically;

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("vklens-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn leftovers(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains("vklens-tmp"))
        .collect()
}

#[test]
fn concurrent_writers_never_mix_their_bytes() {
    let dir = temp_dir("concurrent");
    let target = dir.join("out.bin");
    let contents: Vec<Vec<u8>> = (0..4u8)
        .map(|k| {
            (0..200_000u32)
                .map(|i| (i as u8).wrapping_mul(k + 1))
                .collect()
        })
        .collect();
    std::thread::scope(|s| {
        for c in &contents {
            let target = &target;
            s.spawn(move || {
                for _ in 0..25 {
                    write_atomically(target, |tmp| std::fs::write(tmp, c)).unwrap();
                }
            });
        }
    });
    let got = std::fs::read(&target).unwrap();
    assert!(contents.contains(&got), "the file mixes writers' bytes");
    assert!(leftovers(&dir).is_empty(), "{:?}", leftovers(&dir));
    let _ = std::fs::remove_dir_all(&dir);
}
