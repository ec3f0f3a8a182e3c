//! Rendering and file output: level colours, map, atomic PNG writes, GIF, unwritable directories.

use crowd_sim::render::{Image, Recorder, RenderStyle, render_frame, render_map, write_png_atomic};
use crowd_sim::testing::{ProceduralSource, paper_distance_policy};
use crowd_sim::{Camera, ClipSource, Crowd, CrowdConfig, RenderError};
use glam::Vec3;
use std::path::PathBuf;

fn tmp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("crowd-sim-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

fn stepped_crowd() -> (Crowd<crowd_sim::testing::ProceduralClip>, Camera) {
    let source = ProceduralSource::new();
    let policy = paper_distance_policy(source.levels());
    let cfg = CrowdConfig {
        walkers: 300,
        field_size_m: 120.0,
        seed: 5,
        ..CrowdConfig::default()
    };
    let mut crowd = Crowd::new(&source, cfg).unwrap();
    let cam = Camera {
        position: Vec3::new(0.0, 8.0, -70.0),
        target: Vec3::new(0.0, 0.0, 0.0),
        image_width: 320,
        image_height: 180,
        aspect: 320.0 / 180.0,
        ..Camera::default()
    };
    for _ in 0..5 {
        crowd.step(&source, &policy, &cam, 1.0 / 30.0).unwrap();
    }
    (crowd, cam)
}

fn count_color(img: &Image, c: [u8; 3]) -> usize {
    img.rgb.chunks(3).filter(|p| *p == c).count()
}

#[test]
fn frame_shows_walkers_in_their_level_colours() {
    let (crowd, cam) = stepped_crowd();
    let style = RenderStyle::default();
    let img = render_frame(&crowd, &cam, &style).unwrap();
    assert_eq!((img.width, img.height), (320, 180));
    let levels = crowd.levels().accuracy_levels;
    let mut bins_seen = 0;
    for bin in 0..levels {
        let present = (0..crowd.len()).any(|i| crowd.is_visible(i) && crowd.level_bin(i) == bin);
        let drawn = count_color(&img, style.color_of_bin(bin, levels)) > 0;
        // A level drawn implies a visible walker at that level (colours are distinct).
        assert!(
            !drawn || present,
            "colour of level {bin} drawn without such a walker"
        );
        bins_seen += usize::from(drawn);
    }
    assert!(bins_seen >= 2, "only {bins_seen} levels drawn");
    let map = render_map(&crowd, &cam, &style, 200).unwrap();
    assert!(
        count_color(&map, style.root_only) > 0,
        "culled walkers are drawn grey on the map"
    );
}

#[test]
fn recorder_writes_pngs_maps_and_a_gif_atomically() {
    let (crowd, cam) = stepped_crowd();
    let dir = tmp_dir("rec");
    let mut rec = Recorder::new(&dir, RenderStyle::default()).unwrap();
    for _ in 0..4 {
        rec.record(&crowd, &cam).unwrap();
    }
    let gif = rec.finish().unwrap().gif.unwrap();
    let names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    assert!(names.iter().all(|n| !n.ends_with(".tmp")), "{names:?}");
    assert_eq!(names.iter().filter(|n| n.starts_with("frame_")).count(), 4);
    assert_eq!(names.iter().filter(|n| n.starts_with("map_")).count(), 4);
    // The PNG decodes back to the rendered pixels.
    let dec = png::Decoder::new(std::io::BufReader::new(
        std::fs::File::open(dir.join("frame_00000.png")).unwrap(),
    ));
    let mut reader = dec.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    let img = render_frame(&crowd, &cam, &RenderStyle::default()).unwrap();
    assert_eq!((info.width, info.height), (img.width, img.height));
    assert_eq!(&buf[..info.buffer_size()], &img.rgb[..]);
    assert!(std::fs::read(&gif).unwrap().starts_with(b"GIF89a"));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn unwritable_targets_are_errors_and_keep_earlier_files() {
    let dir = tmp_dir("bad");
    std::fs::create_dir_all(&dir).unwrap();
    // A directory below a regular file cannot be created.
    let file = dir.join("plain-file");
    std::fs::write(&file, b"x").unwrap();
    let e = Recorder::new(file.join("sub"), RenderStyle::default()).unwrap_err();
    assert!(matches!(e, RenderError::Dir { .. }), "{e}");
    // A failed write (the final name is a directory) leaves no temp file and earlier output intact.
    let img = Image::new(8, 8, [1, 2, 3]).unwrap();
    let good = dir.join("good.png");
    write_png_atomic(&good, &img).unwrap();
    let before = std::fs::read(&good).unwrap();
    let blocked = dir.join("blocked.png");
    std::fs::create_dir_all(blocked.join("inner")).unwrap();
    let e = write_png_atomic(&blocked, &img).unwrap_err();
    assert!(matches!(e, RenderError::Io { .. }), "{e}");
    assert!(!dir.join(".blocked.png.tmp").exists());
    assert_eq!(std::fs::read(&good).unwrap(), before);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn render_rejects_a_nan_camera() {
    let (crowd, cam) = stepped_crowd();
    let bad = Camera {
        fov_y: f32::NAN,
        ..cam
    };
    assert!(matches!(
        render_frame(&crowd, &bad, &RenderStyle::default()),
        Err(RenderError::Camera(_))
    ));
}
