//! `regatta transfer`: controllers (worlds) × named conditions (lighting, layouts, noise) →
//! fitness, the table a paper prints. Each cell is a `batch` of the controller's world under
//! the condition, through the same evaluation, so its numbers are those `regatta batch`
//! gives for the same world, overrides, variations and seeds.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context};
use regatta_evolve::variations::Variation;
use regatta_evolve::world::Override;
use regatta_evolve::{Experiment, Fitness, RunSummary};

use crate::outcome::Outcome;

#[derive(clap::Args)]
pub struct Args {
    /// The controllers: worlds whose robots carry them (each a row of the table).
    #[arg(required = true, value_name = "WORLD")]
    controllers: Vec<PathBuf>,
    /// A condition (repeatable; each a column): `NAME: ITEM; ITEM; …`, where an ITEM is
    /// NODE.FIELD=VALUE (set, as `--set`), NODE.FIELD=SPEC (drawn per trial, as `--vary`:
    /// LO..HI, ±D, arena, any) or `world=PATH` (another layout: the controller's robot, with
    /// its controller, network and turret, moved into it, as `batch --network-from`). E.g.
    /// `--condition 'bright: DirectionalLight.intensity=0.8'`. None: the worlds as written.
    #[arg(long = "condition", value_name = "NAME: ITEMS", value_parser = parse_condition)]
    conditions: Vec<Condition>,
    /// Seeds of every cell: a range `1..5` (both ends included) or a list `1,5,9`.
    #[arg(long, default_value = "1..5", value_parser = crate::batch::parse_seeds)]
    seeds: crate::batch::Seeds,
    /// Simulated time per run (s).
    #[arg(long, default_value_t = 600.0, allow_negative_numbers = true)]
    duration: f64,
    /// The fitness of each run: NAME[:key=value,...] (avoidance, regatta, phototaxis).
    #[arg(long, default_value = "regatta", value_parser = regatta_evolve::Fitness::parse)]
    fitness: Fitness,
    /// Threads (0: one per core). The results do not depend on it.
    #[arg(short = 'j', long = "jobs", default_value_t = 0)]
    jobs: usize,
    /// Where runs.csv (one row per run), table.csv (the mean fitness per cell) and the heat
    /// map go.
    #[arg(long, default_value = "out/transfer")]
    out: PathBuf,
    /// File format of the heat map.
    #[arg(long, value_enum, default_value_t)]
    format: crate::plot::FigureFormat,
    #[command(flatten)]
    vary: crate::vary::VaryOptions,
    #[command(flatten)]
    reading: crate::world::WorldOptions,
}

/// One named condition: a world (the controller's own when `None`) with values set and
/// values drawn.
#[derive(Clone, Debug)]
pub struct Condition {
    pub name: String,
    pub world: Option<PathBuf>,
    pub sets: Vec<Override>,
    pub vary: Vec<Variation>,
}

/// Whether an item's value is a variation's SPEC rather than a value to set.
fn is_spec(value: &str) -> bool {
    let value = value.trim();
    matches!(value, "arena" | "any")
        || value.starts_with('±')
        || value.starts_with("+-")
        || value.contains("..")
}

pub(crate) fn parse_condition(text: &str) -> Result<Condition, String> {
    let Some((name, items)) = text.split_once(':') else {
        return Err(format!(
            "a condition is NAME: ITEM; ITEM…, found \"{text}\" (no ':' after a name)"
        ));
    };
    let name = name.trim();
    if name.is_empty() || name.contains(',') {
        return Err(format!(
            "\"{name}\" is not a condition's name (non-empty, no comma)"
        ));
    }
    let mut condition = Condition {
        name: name.to_owned(),
        world: None,
        sets: Vec::new(),
        vary: Vec::new(),
    };
    for item in items.split(';').map(str::trim).filter(|i| !i.is_empty()) {
        let (target, value) = item.split_once('=').unwrap_or((item, ""));
        if target.trim() == "world" {
            condition.world = Some(PathBuf::from(value.trim()));
        } else if is_spec(value) {
            condition
                .vary
                .push(Variation::parse_flag(item).map_err(|e| format!("{name}: {e}"))?);
        } else {
            condition
                .sets
                .push(Override::parse(item).map_err(|e| format!("{name}: {e}"))?);
        }
    }
    Ok(condition)
}

/// One cell's runs.
struct Cell {
    rows: Vec<RunSummary>,
}

impl Cell {
    fn mean(&self, f: impl Fn(&RunSummary) -> f64) -> f64 {
        if self.rows.is_empty() {
            return 0.0;
        }
        self.rows.iter().map(f).sum::<f64>() / self.rows.len() as f64
    }
}

fn visits(row: &RunSummary) -> (usize, u64) {
    row.robots.iter().fold((0, 0), |(v, c), r| {
        (v + r.visits.len(), c + r.fitness.regatta.cyclic_visits)
    })
}

/// The experiment of one cell: the world, overrides and variations `batch` would be given.
fn experiment(
    controller: &Path,
    condition: &Condition,
    args: &Args,
    variations: &[Variation],
) -> anyhow::Result<Experiment> {
    let (world, mut overrides) = match &condition.world {
        Some(layout) => (layout.as_path(), {
            let source = regatta_parser::SourceText::read(controller)
                .with_context(|| format!("cannot read {}", controller.display()))?;
            regatta_evolve::world::controller_overrides(&source.text).with_context(|| {
                format!("cannot take the controller of {}", controller.display())
            })?
        }),
        None => (controller, Vec::new()),
    };
    overrides.extend(condition.sets.iter().cloned());
    let mut all = variations.to_vec();
    all.extend(condition.vary.iter().cloned());
    let name = format!("{} under '{}'", controller.display(), condition.name);
    Experiment::load_with(
        world,
        &args.reading.options()?,
        &overrides,
        regatta_evolve::Driven::Nobody,
    )
    .with_context(|| format!("cannot load {name}"))?
    .with_variations(all)
    .with_context(|| format!("cannot vary {name}"))
}

pub fn run(args: Args) -> anyhow::Result<Outcome> {
    if !(args.duration >= 0.0 && args.duration.is_finite()) {
        bail!("--duration must be a non-negative number of seconds");
    }
    let conditions = if args.conditions.is_empty() {
        vec![Condition {
            name: "as written".to_owned(),
            world: None,
            sets: Vec::new(),
            vary: Vec::new(),
        }]
    } else {
        args.conditions.clone()
    };
    for (i, c) in conditions.iter().enumerate() {
        if conditions[..i].iter().any(|d| d.name == c.name) {
            bail!("--condition '{}' is named twice", c.name);
        }
    }
    let variations = args.vary.all()?;
    let pool = regatta_evolve::thread_pool(args.jobs);
    let names: Vec<String> = args
        .controllers
        .iter()
        .map(|p| crate::world::world_name(p))
        .collect();
    let mut table: Vec<Vec<Cell>> = Vec::new();
    for controller in &args.controllers {
        let mut row = Vec::new();
        for condition in &conditions {
            let experiment = experiment(controller, condition, &args, &variations)?;
            eprint!("{}", experiment.warnings);
            let rows = regatta_evolve::evaluate(
                &experiment,
                None,
                &args.seeds.0,
                &args.fitness,
                experiment.steps_for(args.duration),
                &pool,
                &|| {},
            )?;
            row.push(Cell { rows });
        }
        table.push(row);
    }
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    write_runs(&args.out.join("runs.csv"), &names, &conditions, &table)?;
    write_table(&args.out.join("table.csv"), &names, &conditions, &table)?;
    let figure = regatta_figures::HeatMap {
        title: format!(
            "Transfer: {} fitness, {} s, seeds {}",
            args.fitness.name(),
            args.duration,
            seeds_text(&args.seeds.0)
        ),
        value_label: format!("mean {} fitness", args.fitness.name()),
        // The worlds' stems: a row's label has a third of the figure.
        rows: args
            .controllers
            .iter()
            .map(|p| {
                p.file_stem().map_or_else(
                    || crate::world::world_name(p),
                    |s| s.to_string_lossy().into_owned(),
                )
            })
            .collect(),
        columns: conditions.iter().map(|c| c.name.clone()).collect(),
        values: table
            .iter()
            .map(|row| {
                row.iter()
                    .map(|cell| Some(cell.mean(|r| r.fitness.value)))
                    .collect()
            })
            .collect(),
    };
    let format = regatta_figures::Format::from(args.format);
    let figure_path = args.out.join(format!("transfer.{}", format.extension()));
    regatta_figures::save(&figure, &figure_path, format)
        .with_context(|| format!("cannot write {}", figure_path.display()))?;
    print_table(&names, &conditions, &table, &args.fitness);
    println!(
        "wrote {}, {} and {}",
        args.out.join("runs.csv").display(),
        args.out.join("table.csv").display(),
        figure_path.display()
    );
    Ok(Outcome::Clean)
}

fn seeds_text(seeds: &[u64]) -> String {
    match (seeds.first(), seeds.last()) {
        (Some(a), Some(b)) if seeds.windows(2).all(|w| w[1] == w[0] + 1) && seeds.len() > 2 => {
            format!("{a}..{b}")
        }
        _ => seeds
            .iter()
            .map(u64::to_string)
            .collect::<Vec<_>>()
            .join(","),
    }
}

/// The table on standard output: mean fitness, and mean visits (cyclic) per cell.
fn print_table(names: &[String], conditions: &[Condition], table: &[Vec<Cell>], fitness: &Fitness) {
    let width = names
        .iter()
        .map(|n| n.chars().count())
        .max()
        .unwrap_or(0)
        .max(10);
    let cells: Vec<Vec<String>> = table
        .iter()
        .map(|row| {
            row.iter()
                .map(|cell| {
                    let fitness = cell.mean(|r| r.fitness.value);
                    let all = cell.mean(|r| visits(r).0 as f64);
                    let cyclic = cell.mean(|r| visits(r).1 as f64);
                    format!("{fitness:.3} ({all:.1}/{cyclic:.1})")
                })
                .collect()
        })
        .collect();
    let column = |c: usize| {
        cells
            .iter()
            .map(|row| row[c].chars().count())
            .chain([conditions[c].name.chars().count()])
            .max()
            .unwrap_or(0)
    };
    println!(
        "mean {} fitness per cell (mean buoy visits / cyclic visits per run)",
        fitness.name()
    );
    let mut header = format!("{:width$}", "controller");
    for (c, condition) in conditions.iter().enumerate() {
        header.push_str(&format!("  {:>w$}", condition.name, w = column(c)));
    }
    println!("{header}");
    for (name, row) in names.iter().zip(&cells) {
        let mut line = format!("{name:width$}");
        for (c, cell) in row.iter().enumerate() {
            line.push_str(&format!("  {cell:>w$}", w = column(c)));
        }
        println!("{line}");
    }
}

fn csv_writer(path: &Path) -> anyhow::Result<csv::Writer<std::fs::File>> {
    csv::Writer::from_path(path).with_context(|| format!("cannot write {}", path.display()))
}

/// One row per run: which cell, the seed, the fitness and the buoy visits; with the values
/// the run's variations drew (`key=value` pairs, `;`-separated).
fn write_runs(
    path: &Path,
    names: &[String],
    conditions: &[Condition],
    table: &[Vec<Cell>],
) -> anyhow::Result<()> {
    let mut out = csv_writer(path)?;
    out.write_record([
        "controller",
        "condition",
        "seed",
        "fitness",
        "distance_m",
        "visits",
        "cyclic_visits",
        "variations",
    ])?;
    for (name, row) in names.iter().zip(table) {
        for (condition, cell) in conditions.iter().zip(row) {
            for run in &cell.rows {
                let (v, c) = visits(run);
                let distance: f64 = run.robots.iter().map(|r| r.distance_m).sum();
                let drawn: Vec<String> = run
                    .variations
                    .iter()
                    .map(|d| format!("{}={}", d.key(), d.value))
                    .collect();
                out.write_record([
                    name.clone(),
                    condition.name.clone(),
                    run.seed.to_string(),
                    format!("{:?}", run.fitness.value),
                    format!("{distance:?}"),
                    v.to_string(),
                    c.to_string(),
                    drawn.join(";"),
                ])?;
            }
        }
    }
    out.flush()?;
    Ok(())
}

/// The mean fitness per cell: a row per controller, a column per condition.
fn write_table(
    path: &Path,
    names: &[String],
    conditions: &[Condition],
    table: &[Vec<Cell>],
) -> anyhow::Result<()> {
    let mut out = csv_writer(path)?;
    let mut header = vec!["controller".to_owned()];
    header.extend(conditions.iter().map(|c| c.name.clone()));
    out.write_record(&header)?;
    for (name, row) in names.iter().zip(table) {
        let mut record = vec![name.clone()];
        record.extend(
            row.iter()
                .map(|cell| format!("{:?}", cell.mean(|r| r.fitness.value))),
        );
        out.write_record(&record)?;
    }
    out.flush()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn conditions_read_sets_variations_and_layouts() {
        let c = parse_condition(
            "wide bright: world=worlds/regatta_wide.wbt; DirectionalLight.intensity=0.8; Buoy.translation=±0.05",
        )
        .unwrap();
        assert_eq!(c.name, "wide bright");
        assert_eq!(
            c.world.as_deref(),
            Some(Path::new("worlds/regatta_wide.wbt"))
        );
        assert_eq!(c.sets.len(), 1);
        assert_eq!(c.vary.len(), 1);
        assert!(parse_condition("no name").is_err());
        let error = parse_condition("x: Buoy.radius=3..1").unwrap_err();
        assert!(error.contains("--vary 'Buoy.radius=3..1'"), "{error}");
    }
}
