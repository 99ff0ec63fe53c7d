//! Image output: PFM and EXR round trips are bit-exact, PNG holds the expected sRGB bytes, and writes are
//! atomic (a failed write leaves nothing behind and the old file as it was).

use std::path::Path;

use glam::Vec3;
use plie::io::image::decode_pfm;
use plie::io::{load_pfm, save_image, write_atomic};
use plie::Error;

/// 3 x 2 pixels with awkward values: negative zero, a subnormal, huge, tiny, negative, NaN.
fn awkward() -> Vec<Vec3> {
    vec![
        Vec3::new(0.0, -0.0, 1.0),
        Vec3::new(f32::MIN_POSITIVE / 4.0, 1e30, 0.1),
        Vec3::new(-2.5, 3.0e-7, 17.0),
        Vec3::new(f32::NAN, 0.5, 1.0 / 3.0),
        Vec3::new(123456.79, 1e-38, 2.0),
        Vec3::new(0.333, 0.666, 0.999),
    ]
}

fn bits(p: &[Vec3]) -> Vec<u32> {
    p.iter().flat_map(|v| v.to_array()).map(f32::to_bits).collect()
}

#[test]
fn pfm_round_trip_is_bit_exact() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("a.pfm");
    save_image(&path, 3, 2, &awkward()).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    assert!(bytes.starts_with(b"PF\n3 2\n-1.0\n"));
    // Bottom row first: the first stored pixel is pixel (0, 1).
    assert_eq!(&bytes[12..16], &f32::NAN.to_le_bytes());
    let (w, h, pixels) = load_pfm(&path).unwrap();
    assert_eq!((w, h), (3, 2));
    assert_eq!(bits(&pixels), bits(&awkward()));
}

#[test]
fn pfm_reader_rejects_bad_files() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("a.pfm");
    save_image(&path, 3, 2, &awkward()).unwrap();
    let good = std::fs::read(&path).unwrap();
    let truncated = &good[..good.len() - 1];
    let msg = decode_pfm(truncated).unwrap_err();
    assert!(msg.contains("truncated"), "{msg}");
    let mut trailing = good.clone();
    trailing.push(0);
    assert!(decode_pfm(&trailing).unwrap_err().contains("trailing"));
    assert!(decode_pfm(b"PF\n3 x\n-1.0\n").unwrap_err().contains("dimension"));
    std::fs::write(&path, &good[..20]).unwrap();
    match load_pfm(&path) {
        Err(Error::Parse { path: p, .. }) => assert_eq!(p, path),
        r => panic!("expected a parse error, got {r:?}"),
    }
    // Big-endian (positive scale) files read too.
    let mut be = b"PF\n1 1\n1.0\n".to_vec();
    for c in [1.0f32, 2.0, 3.0] {
        be.extend(c.to_be_bytes());
    }
    assert_eq!(decode_pfm(&be).unwrap().2, [Vec3::new(1.0, 2.0, 3.0)]);
}

#[test]
fn exr_round_trip_is_bit_exact() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("a.exr");
    let img: Vec<Vec3> = awkward().into_iter().filter(|v| !v.is_nan()).chain([Vec3::splat(7.0)]).collect();
    save_image(&path, 3, 2, &img).unwrap();
    let read = image::open(&path).unwrap().into_rgb32f();
    assert_eq!(read.dimensions(), (3, 2));
    let back: Vec<Vec3> = read.pixels().map(|p| Vec3::from(p.0)).collect();
    assert_eq!(bits(&back), bits(&img));
}

#[test]
fn png_holds_srgb_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("a.png");
    let img = [
        Vec3::new(0.0, 1.0, 0.5),
        Vec3::new(0.18, 0.001, 0.0031308),
        Vec3::new(-1.0, 5.0, f32::NAN),
        Vec3::new(0.25, 0.75, 0.9),
    ];
    save_image(&path, 2, 2, &img).unwrap();
    let read = image::open(&path).unwrap().into_rgb8();
    assert_eq!(read.dimensions(), (2, 2));
    let expected: [u8; 12] = [0, 255, 188, 118, 3, 10, 0, 255, 0, 137, 225, 243];
    assert_eq!(read.as_raw().as_slice(), &expected);
}

#[test]
fn bad_requests() {
    let dir = tempfile::tempdir().unwrap();
    let img = [Vec3::ONE; 4];
    match save_image(&dir.path().join("a.jpg"), 2, 2, &img) {
        Err(e @ Error::Image { .. }) => assert!(e.to_string().contains(".png, .exr, .pfm"), "{e}"),
        r => panic!("expected an image error, got {r:?}"),
    }
    assert!(save_image(&dir.path().join("a.pfm"), 3, 2, &img).is_err(), "pixel count mismatch");
    assert!(save_image(&dir.path().join("a.png"), 0, 0, &[]).is_err(), "empty image");
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0, "nothing written");
}

#[test]
fn missing_directory_is_an_io_error_and_creates_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("no/such/dir");
    let path = missing.join("a.png");
    match save_image(&path, 1, 1, &[Vec3::ONE]) {
        Err(e @ Error::Io { .. }) => {
            let Error::Io { path: p, .. } = &e else { unreachable!() };
            assert_eq!(p, &path);
            assert!(e.to_string().contains("no/such/dir"), "{e}");
        }
        r => panic!("expected an I/O error, got {r:?}"),
    }
    assert!(!dir.path().join("no").exists());
}

#[test]
fn parent_that_is_a_file_is_an_io_error() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("plain"), b"x").unwrap();
    let path = dir.path().join("plain/a.pfm");
    match save_image(&path, 1, 1, &[Vec3::ONE]) {
        Err(Error::Io { path: p, .. }) => assert_eq!(p, path),
        r => panic!("expected an I/O error, got {r:?}"),
    }
    assert_eq!(std::fs::read(dir.path().join("plain")).unwrap(), b"x");
}

#[test]
fn failed_write_leaves_the_target_unchanged() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("out.pfm");
    std::fs::write(&path, b"old contents").unwrap();
    let r = write_atomic(&path, |w| {
        w.write_all(b"half of a new file").unwrap();
        Err(Error::Image { path: path.clone(), message: "encoder failed".into() })
    });
    assert!(matches!(r, Err(Error::Image { .. })));
    assert_eq!(std::fs::read(&path).unwrap(), b"old contents");
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1, "temporary file removed");
    // A successful write replaces it whole.
    save_image(&path, 1, 1, &[Vec3::ONE]).unwrap();
    assert_eq!(load_pfm(&path).unwrap().2, [Vec3::ONE]);
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
}

#[test]
fn writing_over_a_directory_fails_cleanly() {
    let dir = tempfile::tempdir().unwrap();
    let target = dir.path().join("taken.pfm");
    std::fs::create_dir(&target).unwrap();
    assert!(save_image(&target, 1, 1, &[Vec3::ONE]).is_err());
    assert!(Path::new(&target).is_dir());
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1, "temporary file removed");
}
