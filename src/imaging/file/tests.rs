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

#[test]
fn the_header_says_whether_the_pixels_load_as_8_bit_and_rgb_keeps_its_values() {
    use crate::imaging::{BitDepth, Pixels};
    let dir = temp_dir("header");
    let rgb = dir.join("rgb.png");
    let rgb16 = dir.join("rgb16.png");
    let text = dir.join("not.png");
    image::RgbImage::from_fn(3, 2, |x, y| image::Rgb([x as u8 * 80, y as u8 * 90, 7]))
        .save(&rgb)
        .unwrap();
    image::ImageBuffer::<image::Rgb<u16>, _>::from_fn(3, 2, |x, _| {
        image::Rgb([x as u16 * 9000, 1, 2])
    })
    .save(&rgb16)
    .unwrap();
    std::fs::write(&text, "not an image").unwrap();
    assert_eq!(super::is_eight_bit(&rgb), Some(true));
    assert_eq!(super::is_eight_bit(&rgb16), Some(false));
    assert_eq!(super::is_eight_bit(&text), None);
    // An RGB photo loads as opaque RGBA8 and, written back as RGB, keeps every value.
    let (raster, channels) = super::load_with_channels(&rgb).unwrap();
    assert_eq!((channels.0, raster.bit_depth), (3, BitDepth::U8));
    let Pixels::Rgba8(p) = &raster.pixels else {
        panic!("{:?}", raster.bit_depth)
    };
    assert_eq!(p[4], [80, 90, 7, 255]);
    let again = dir.join("again.png");
    super::save_as(&raster, &again, channels).unwrap();
    assert_eq!(
        image::open(&again).unwrap().to_rgb8(),
        image::open(&rgb).unwrap().to_rgb8()
    );
    assert_eq!(image::open(&again).unwrap().color(), image::ColorType::Rgb8);
    let _ = std::fs::remove_dir_all(&dir);
}
