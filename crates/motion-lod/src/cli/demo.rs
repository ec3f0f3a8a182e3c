//! `motion-lod demo`: the main job on the embedded data: build a model from the procedural walker's takes,
//! run 1,000 walkers for 10 s with the distance policy, render a few frames and compare with naive
//! interpolation on the same crowd; also writes a 3 s clip of 24 of its walkers as `crowd.glb`.

use std::path::PathBuf;

use clap::Args;

use super::crowd::{CrowdArgs, PolicyArg};

/// Arguments of `motion-lod demo`.
#[derive(Debug, Args)]
pub struct DemoArgs {
    /// Number of walkers (1..=1000000).
    #[arg(long, default_value_t = 1000, value_parser = super::ranges::count(super::ranges::WALKERS))]
    pub walkers: usize,
    /// Simulated seconds (0.001 to 3600).
    #[arg(long, default_value_t = 10.0, value_parser = super::ranges::seconds)]
    pub seconds: f32,
    /// Where to write the rendered frames, maps, GIF and the glTF clip `crowd.glb`.
    #[arg(long, default_value = "out/demo")]
    pub render: PathBuf,
}

/// Runs the subcommand.
pub fn run(args: DemoArgs) -> anyhow::Result<()> {
    out!("building a model from the embedded data set (procedural walker, 3 performers, 120 Hz)");
    super::crowd::run(CrowdArgs {
        model: None,
        walkers: args.walkers,
        seconds: args.seconds,
        density: 0.05,
        fps: 30.0,
        seed: 1,
        policy: PolicyArg::Distance,
        camera: super::crowd::CameraArg::Ground,
        culling: super::crowd::CullingArg::Scan,
        no_lod: false,
        naive: false,
        compare_naive: true,
        pca: false,
        compare_pca: false,
        pca_rank: 40,
        render: Some(args.render.clone()),
        render_every: 30,
        json: false,
        style: None,
        export: Some(args.render.join("crowd.glb")),
        export_walkers: 24,
        export_seconds: 3.0,
        gpu: false,
        joint_slots: None,
    })?;
    out!(
        "the crowd as a 3D file: {} (glTF 2.0, any engine or viewer); in a browser: motion-lod view {}",
        args.render.join("crowd.glb").display(),
        args.render.join("crowd.glb").display()
    );
    Ok(())
}
