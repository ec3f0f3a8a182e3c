//! Runs a procedural crowd and renders it: `cargo run -p crowd-sim --example crowd_demo -- DIR
//! [walkers] [frames]`. Writes `frame_NNNNN.png`, `map_NNNNN.png` and `crowd.gif` into DIR and
//! prints the crowd report.

use crowd_sim::render::{Recorder, RenderStyle};
use crowd_sim::testing::{ProceduralSource, paper_distance_policy};
use crowd_sim::{Camera, CameraPath, ClipSource, Crowd, CrowdConfig, CrowdReport};
use glam::Vec3;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let dir = args
        .next()
        .ok_or("usage: crowd_demo DIR [walkers] [frames]")?;
    let walkers: usize = args.next().map(|s| s.parse()).transpose()?.unwrap_or(300);
    let frames: usize = args.next().map(|s| s.parse()).transpose()?.unwrap_or(60);
    let source = ProceduralSource::new();
    let policy = paper_distance_policy(source.levels());
    let config = CrowdConfig {
        walkers,
        field_size_m: 160.0,
        ..CrowdConfig::default()
    };
    let mut crowd = Crowd::new(&source, config)?;
    let path = CameraPath::Orbit {
        centre: Vec3::ZERO,
        radius: 60.0,
        height: 12.0,
        period_s: 40.0,
    };
    let lens = Camera {
        image_width: 800,
        image_height: 450,
        aspect: 800.0 / 450.0,
        ..Camera::default()
    };
    let mut rec = Recorder::new(&dir, RenderStyle::default())?;
    let mut report = CrowdReport::new();
    for f in 0..frames {
        let cam = path.camera_at(f as f32 / config.fps, &lens);
        report.add(&crowd.step(&source, &policy, &cam, 1.0 / config.fps)?);
        rec.record(&crowd, &cam)?;
    }
    rec.finish()?;
    println!("{report}");
    Ok(())
}
