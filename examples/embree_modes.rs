//! Prints the Embree modes table for one scene, until `ember bench accel` runs it:
//! `cargo run --release --features embree4 --example embree_modes -- SCENE.dae [THREADS]`
//! (and the same with `--features embree` for Embree 3).

use ember::bench::embree_modes::{embree_modes, markdown, EmbreeModesOptions};

fn main() -> anyhow::Result<()> {
    let mut args = std::env::args().skip(1);
    let scene = args
        .next()
        .ok_or_else(|| anyhow::anyhow!("usage: embree_modes SCENE.dae [THREADS]"))?;
    let mut opts = EmbreeModesOptions::default();
    if let Some(t) = args.next() {
        opts.threads = t.parse()?;
    }
    let scene = ember::scene::collada::load(std::path::Path::new(&scene))?;
    print!("{}", markdown(&embree_modes(&scene, &opts)?));
    Ok(())
}
