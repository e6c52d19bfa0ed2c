//! `--vary NODE.FIELD=SPEC` and `--variations FILE`: the flags of every command that draws a
//! world's values anew for each trial (`run`, `batch`, `evolve`, `transfer`).

use std::path::PathBuf;

use anyhow::Context;
use regatta_evolve::variations::{parse_file, Variation};

/// Values drawn per trial from its seed, recorded in every result.
#[derive(clap::Args, Clone, Debug, Default)]
pub struct VaryOptions {
    /// Draw a field anew for each trial from its seed (repeatable): NODE.FIELD=SPEC, every
    /// node of that type or DEF name its own draw. SPEC is LO..HI (uniform), ±D or +-D (the
    /// world's value moved by up to D: a scalar, a position's horizontal components, a
    /// rotation's angle), A|B|… (one of the values, each as likely: `Buoy.irReflectance=0.5|1`), `arena` (a position anywhere on the arena's floor) or `any` (a
    /// heading). NODE.count=SPEC (LO..HI, A|B|… or one number) keeps that many of the nodes,
    /// the ones kept drawn too: `Buoy.count=2..4`. A draw that puts a robot in a buoy or a
    /// buoy outside the arena is drawn again. E.g. `--vary 'DirectionalLight.intensity=0.02..0.8' --vary 'Buoy.translation=±0.1'`.
    #[arg(long = "vary", value_name = "NODE.FIELD=SPEC", value_parser = parse_vary)]
    pub vary: Vec<Variation>,
    /// Variations from a TOML file: a table per node type or DEF name, FIELD = "SPEC" in
    /// it (`[Buoy]` then `irReflectance = "0.5..1"`); drawn before the `--vary` flags.
    #[arg(long, value_name = "FILE.toml")]
    pub variations: Option<PathBuf>,
}

fn parse_vary(text: &str) -> Result<Variation, String> {
    Variation::parse_flag(text).map_err(|e| e.to_string())
}

impl VaryOptions {
    /// Every variation, the file's first.
    pub fn all(&self) -> anyhow::Result<Vec<Variation>> {
        let mut all = Vec::new();
        if let Some(path) = &self.variations {
            let text = std::fs::read_to_string(path)
                .with_context(|| format!("cannot read {}", path.display()))?;
            all = parse_file(&path.display().to_string(), &text)?;
        }
        all.extend(self.vary.iter().cloned());
        Ok(all)
    }
}

/// The world at `path` as the trial under `seed` (the world's own seed when `None`) draws
/// it: checked and compiled like [`crate::world::load`], with the values it drew.
pub fn load_varied(
    path: &std::path::Path,
    world: &crate::world::WorldOptions,
    seed: Option<u64>,
    variations: Vec<Variation>,
    color: bool,
) -> anyhow::Result<crate::world::Loaded> {
    let name = crate::world::world_name(path);
    let experiment = regatta_evolve::Experiment::load_with(
        path,
        &world.options()?,
        &[],
        regatta_evolve::Driven::Nobody,
    )
    .with_context(|| format!("cannot load {name}"))?
    .with_variations(variations)
    .with_context(|| format!("cannot vary {name}"))?;
    let seed = seed.unwrap_or(experiment.compiled.settings.seed);
    let varied = experiment.for_seed(seed)?.unwrap_or(experiment);
    let mut loaded = crate::world::load_text(path, &varied.text, world, color)?;
    loaded.drawn = varied.drawn;
    Ok(loaded)
}
