//! What the write-up shows: the course's five parts as rows of renders (each a
//! [`Recipe`]), part 2's timing table and the convergence charts, at full size or
//! `--quick`. Nothing here renders; [`super::run`] carries the plan out.

use super::recipe::Recipe;
use crate::accel::Backend;
use crate::render::Shading;
use anyhow::Result;
use std::path::{Path, PathBuf};

/// Sizes and sample counts: the full write-up, or `--quick`'s small one.
#[derive(Clone, Debug, PartialEq)]
pub struct Budget {
    /// Normal-shaded renders of parts 1 and 2.
    pub normals: (u32, u32),
    pub normals_spp: u32,
    /// Part 3's renders (at 1 sample per pixel, as the course asks).
    pub direct: (u32, u32),
    pub light_rays: Vec<u32>,
    /// Part 4's renders.
    pub global: (u32, u32),
    /// Samples (and `-l`) of part 4's direct/indirect and max-depth rows.
    pub global_spp: u32,
    pub global_light_rays: u32,
    /// Part 4's row of sample counts (at `-l` [`Budget::global_light_rays`]).
    pub spp_series: Vec<u32>,
    /// Part 5: resolution, the most samples a pixel takes, batch and tolerance.
    pub adaptive: (u32, u32),
    pub adaptive_spp: u32,
    pub adaptive_batch: u32,
    /// Part 2's table: the resolution of its timed normal-shaded renders, and how many
    /// times each BVH render runs (the median is shown).
    pub timing: (u32, u32),
    pub timing_repeats: usize,
    /// Section 6: the convergence runs' largest spp and time per point.
    pub converge_max_spp: u32,
    pub converge_max_seconds: f64,
}

impl Budget {
    /// The write-up at the course's sizes where the time allows (under 15 minutes on
    /// two cores; the README gives the measured time).
    pub fn full() -> Budget {
        Budget {
            normals: (480, 360),
            normals_spp: 4,
            direct: (480, 360),
            light_rays: vec![1, 4, 16, 64],
            global: (480, 360),
            global_spp: 128,
            global_light_rays: 4,
            spp_series: vec![1, 2, 4, 8, 16, 64, 1024],
            adaptive: (320, 240),
            adaptive_spp: 2048,
            adaptive_batch: 64,
            timing: (320, 240),
            timing_repeats: 3,
            converge_max_spp: 256,
            converge_max_seconds: 2.0,
        }
    }

    /// Small sizes and sample counts: every part, in about 5 to 10 seconds on two cores.
    pub fn quick() -> Budget {
        Budget {
            normals: (160, 120),
            normals_spp: 1,
            direct: (160, 120),
            light_rays: vec![1, 4, 16, 64],
            global: (160, 120),
            global_spp: 16,
            global_light_rays: 1,
            spp_series: vec![1, 4, 16, 64],
            adaptive: (120, 90),
            adaptive_spp: 256,
            adaptive_batch: 32,
            timing: (64, 48),
            timing_repeats: 1,
            converge_max_spp: 16,
            converge_max_seconds: 0.5,
        }
    }
}

/// The tolerance of part 5's `-a` (the course's 0.05).
pub const ADAPTIVE_TOLERANCE: f32 = 0.05;

/// One image: its file (relative to the page) and label, and how it is made.
#[derive(Clone, Debug)]
pub struct Shot {
    pub file: String,
    pub label: String,
    pub make: Make,
}

#[derive(Clone, Debug)]
pub enum Make {
    /// One render; with `-a`, its sample-rate map `<file stem>_rate.png` too.
    Render(Recipe),
    /// `full − minus`, pixel by pixel, of two renders with the same seed: their paths
    /// agree up to `minus`'s depth, so the difference is exactly the longer paths.
    Difference { full: Recipe, minus: Recipe },
}

/// One part of the plan, in page order.
#[derive(Clone, Debug)]
pub enum Planned {
    Text(String),
    Figures {
        caption: String,
        shots: Vec<Shot>,
    },
    /// Part 2's table of render times per backend.
    BvhTable {
        scenes: Vec<PathBuf>,
    },
    /// Section 6: `ember bench converge` on a scene, against a Mitsuba reference.
    Converge(ConvergeCase),
}

/// One convergence run of section 6.
#[derive(Clone, Debug, PartialEq)]
pub struct ConvergeCase {
    pub scene: PathBuf,
    pub max_depth: u32,
    /// The Mitsuba 3 reference (tests/data/references) of the scene at this depth,
    /// when the scene has one; else ember renders its own.
    pub reference: Option<String>,
}

#[derive(Clone, Debug)]
pub struct PlannedSection {
    pub id: &'static str,
    pub title: &'static str,
    pub items: Vec<Planned>,
}

/// The scenes each part uses: the course's, or the user's for every part.
#[derive(Clone, Debug)]
pub struct Scenes {
    pub normals: Vec<PathBuf>,
    pub meshes: Vec<PathBuf>,
    pub direct: Vec<PathBuf>,
    /// Part 4's direct/indirect split and sample-count rows.
    pub global: PathBuf,
    /// Part 4's max-depth rows.
    pub depth: PathBuf,
    pub adaptive: Vec<PathBuf>,
    pub converge: Vec<ConvergeCase>,
}

impl Scenes {
    /// The course's scenes (as the CS184 write-up uses them), from ember's data folder.
    pub fn course(quick: bool) -> Result<Scenes> {
        let s = |rel: &str| crate::data::scene(rel);
        let (bunny, spheres) = (
            s("cs184/sky/CBbunny.dae")?,
            s("cs184/sky/CBspheres_lambertian.dae")?,
        );
        let normals = match quick {
            false => vec![
                spheres.clone(),
                s("cs184/sky/CBgems.dae")?,
                s("cs184/sky/CBcoil.dae")?,
                s("cs184/keenan/banana.dae")?,
            ],
            true => vec![spheres.clone(), s("cs184/sky/CBgems.dae")?],
        };
        let meshes = match quick {
            false => ["cow", "teapot", "beetle", "peter", "maxplanck"]
                .iter()
                .map(|m| s(&format!("cs184/meshedit/{m}.dae")))
                .chain([Ok(bunny.clone())])
                .collect::<Result<Vec<_>>>()?,
            true => vec![
                s("cs184/meshedit/cow.dae")?,
                s("cs184/meshedit/maxplanck.dae")?,
            ],
        };
        let case = |scene: &PathBuf, m: u32| ConvergeCase {
            scene: scene.clone(),
            max_depth: m,
            reference: Some(format!("{}_m{m}.exr", stem(scene))),
        };
        let converge = match quick {
            false => vec![case(&spheres, 1), case(&bunny, 5)],
            true => vec![case(&spheres, 1)],
        };
        Ok(Scenes {
            normals,
            meshes,
            direct: vec![bunny.clone(), spheres.clone()],
            global: spheres.clone(),
            depth: bunny.clone(),
            adaptive: vec![bunny, spheres],
            converge,
        })
    }

    /// The user's scenes in every part; part 4's rows and section 6 use the first.
    pub fn given(scenes: &[PathBuf]) -> Scenes {
        let first = scenes[0].clone();
        Scenes {
            normals: scenes.to_vec(),
            meshes: scenes.to_vec(),
            direct: scenes.to_vec(),
            global: first.clone(),
            depth: first.clone(),
            adaptive: scenes.to_vec(),
            converge: vec![ConvergeCase {
                scene: first,
                max_depth: 1,
                reference: None,
            }],
        }
    }
}

/// `path`'s file stem.
pub fn stem(path: &Path) -> String {
    path.file_stem()
        .map_or("scene".into(), |s| s.to_string_lossy().into_owned())
}

/// The write-up's sections.
pub fn plan(scenes: &Scenes, b: &Budget, seed: u64) -> Vec<PlannedSection> {
    vec![
        part1(scenes, b, seed),
        part2(scenes, b, seed),
        part3(scenes, b, seed),
        part4(scenes, b, seed),
        part5(scenes, b, seed),
        PlannedSection {
            id: "part6",
            title: "Speed against accuracy",
            items: scenes
                .converge
                .iter()
                .cloned()
                .map(Planned::Converge)
                .collect(),
        },
    ]
}

fn normals(scene: &Path, b: &Budget, seed: u64) -> Recipe {
    Recipe {
        shading: Shading::Normals,
        spp: b.normals_spp,
        ..Recipe::new(scene.to_path_buf(), b.normals, seed)
    }
}

fn part1(scenes: &Scenes, b: &Budget, seed: u64) -> PlannedSection {
    let shots = scenes
        .normals
        .iter()
        .map(|s| Shot {
            file: format!("figures/part1_{}.png", stem(s)),
            label: stem(s),
            make: Make::Render(normals(s, b, seed)),
        })
        .collect();
    PlannedSection {
        id: "part1",
        title: "Part 1: Ray generation and scene intersection",
        items: vec![
            Planned::Text("Every pixel shows `0.5·n + 0.5` of the shading normal its camera rays hit (`--shading normals`): camera rays through the pixel, tested against every triangle and sphere of the scene.".into()),
            Planned::Figures { caption: "Normal shading of small scenes".into(), shots },
        ],
    }
}

fn part2(scenes: &Scenes, b: &Budget, seed: u64) -> PlannedSection {
    let shots = scenes
        .meshes
        .iter()
        .map(|s| Shot {
            file: format!("figures/part2_{}.png", stem(s)),
            label: stem(s),
            make: Make::Render(normals(s, b, seed)),
        })
        .collect();
    PlannedSection {
        id: "part2",
        title: "Part 2: Bounding volume hierarchy",
        items: vec![
            Planned::Text("Large meshes, normal-shaded (the table below gives each one's triangle count): with ember's BVH (binned surface-area heuristic, 16 children per node) each renders in a fraction of a second.".into()),
            Planned::Figures { caption: "Large meshes".into(), shots },
            Planned::BvhTable { scenes: scenes.meshes.clone() },
        ],
    }
}

fn part3(scenes: &Scenes, b: &Budget, seed: u64) -> PlannedSection {
    let mut items = vec![Planned::Text(
        "Direct lighting only (`-m 1`) at 1 sample per pixel, with 1, 4, 16 and 64 light rays (`-l`) at every shading point. Uniform hemisphere sampling (`-H`) finds the area light only when a random direction happens to hit it, so its noise falls slowly as `-l` grows; light sampling (the default) aims every ray at the light, and its soft shadows smooth out.".into(),
    )];
    for scene in &scenes.direct {
        for (hemisphere, name, slug) in [
            (true, "uniform hemisphere sampling (-H)", "hemisphere"),
            (false, "light sampling", "light"),
        ] {
            let shots = b.light_rays.iter().map(|&l| Shot {
                file: format!("figures/part3_{}_{slug}_l{l}.png", stem(scene)),
                label: format!("-l {l}"),
                make: Make::Render(Recipe {
                    hemisphere,
                    light_samples: l,
                    ..Recipe::new(scene.clone(), b.direct, seed)
                }),
            });
            items.push(Planned::Figures {
                caption: format!("{}: {name}", stem(scene)),
                shots: shots.collect(),
            });
        }
    }
    PlannedSection {
        id: "part3",
        title: "Part 3: Direct illumination",
        items,
    }
}

fn global(scene: &Path, b: &Budget, seed: u64) -> Recipe {
    Recipe {
        spp: b.global_spp,
        light_samples: b.global_light_rays,
        ..Recipe::new(scene.to_path_buf(), b.global, seed)
    }
}

fn part4(scenes: &Scenes, b: &Budget, seed: u64) -> PlannedSection {
    let g = &scenes.global;
    let name = stem(g);
    let direct = Recipe {
        max_depth: 1,
        ..global(g, b, seed)
    };
    let full = Recipe {
        max_depth: 5,
        ..global(g, b, seed)
    };
    let split = vec![
        Shot {
            file: format!("figures/part4_{name}_direct.png"),
            label: "direct only (-m 1)".into(),
            make: Make::Render(direct.clone()),
        },
        Shot {
            file: format!("figures/part4_{name}_indirect.png"),
            label: "indirect only (bounces 2 to 5)".into(),
            make: Make::Difference {
                full: full.clone(),
                minus: direct,
            },
        },
        Shot {
            file: format!("figures/part4_{name}_global.png"),
            label: "both (-m 5)".into(),
            make: Make::Render(full),
        },
    ];
    let d = &scenes.depth;
    let depth_row = |accumulate: bool| -> Vec<Shot> {
        (0..=5)
            .map(|m| Shot {
                file: format!(
                    "figures/part4_{}_m{m}{}.png",
                    stem(d),
                    if accumulate { "" } else { "_o0" }
                ),
                label: format!("-m {m}{}", if accumulate { "" } else { " -o 0" }),
                make: Make::Render(Recipe {
                    max_depth: m,
                    accumulate,
                    ..global(d, b, seed)
                }),
            })
            .collect()
    };
    let spp_row = b.spp_series.iter().map(|&spp| Shot {
        file: format!("figures/part4_{name}_s{spp}.png"),
        label: format!("-s {spp}"),
        make: Make::Render(Recipe {
            spp,
            max_depth: 5,
            ..global(g, b, seed)
        }),
    });
    PlannedSection {
        id: "part4",
        title: "Part 4: Global illumination",
        items: vec![
            Planned::Text(format!("Paths of up to `-m` bounces, at {} samples per pixel and `-l {}`. Indirect light alone is the difference of the two renders beside it, which share their seed and so their paths: what remains is exactly the light of the paths of 2 to 5 bounces (ember has no flag for it).", b.global_spp, b.global_light_rays)),
            Planned::Figures { caption: format!("{name}: direct and indirect illumination"), shots: split },
            Planned::Figures { caption: format!("{}: max ray depth 0 to 5, bounces accumulated", stem(d)), shots: depth_row(true) },
            Planned::Figures { caption: format!("{}: only the m-th bounce (-o 0)", stem(d)), shots: depth_row(false) },
            Planned::Figures { caption: format!("{name}: samples per pixel (-m 5, -l {})", b.global_light_rays), shots: spp_row.collect() },
        ],
    }
}

fn part5(scenes: &Scenes, b: &Budget, seed: u64) -> PlannedSection {
    let shots = scenes.adaptive.iter().map(|s| Shot {
        file: format!("figures/part5_{}.png", stem(s)),
        label: stem(s),
        make: Make::Render(Recipe {
            spp: b.adaptive_spp,
            adaptive: Some((b.adaptive_batch, ADAPTIVE_TOLERANCE)),
            max_depth: 5,
            ..Recipe::new(s.clone(), b.adaptive, seed)
        }),
    });
    PlannedSection {
        id: "part5",
        title: "Part 5: Adaptive sampling",
        items: vec![
            Planned::Text(format!("`-a {} {ADAPTIVE_TOLERANCE}`: after every batch of {} samples a pixel stops once its 95 % confidence interval is within {} % of its mean, or at `-s {}`. Beside each render, its sample-rate map (written by the same command as `NAME_rate.png`): blue pixels stopped early, red ones took all {} samples.", b.adaptive_batch, b.adaptive_batch, ADAPTIVE_TOLERANCE * 100.0, b.adaptive_spp, b.adaptive_spp)),
            Planned::Figures { caption: "Adaptive sampling and sample rates".into(), shots: shots.collect() },
        ],
    }
}

/// The normal-shaded render part 2's table times for `scene` on `backend`.
pub fn timing_recipe(scene: &Path, b: &Budget, backend: Backend, seed: u64) -> Recipe {
    Recipe {
        shading: Shading::Normals,
        accel: backend,
        ..Recipe::new(scene.to_path_buf(), b.timing, seed)
    }
}

/// Every render of the plan (the figures' and the timing table's), in plan order.
pub fn recipes(sections: &[PlannedSection], b: &Budget, seed: u64) -> Vec<Recipe> {
    let mut out = Vec::new();
    for item in sections.iter().flat_map(|s| &s.items) {
        match item {
            Planned::Figures { shots, .. } => {
                for shot in shots {
                    match &shot.make {
                        Make::Render(r) => out.push(r.clone()),
                        Make::Difference { full, minus } => {
                            out.extend([full.clone(), minus.clone()])
                        }
                    }
                }
            }
            Planned::BvhTable { scenes } => {
                for s in scenes {
                    out.extend(
                        timed_backends()
                            .into_iter()
                            .map(|k| timing_recipe(s, b, k, seed)),
                    );
                }
            }
            Planned::Text(_) | Planned::Converge(_) => {}
        }
    }
    out
}

/// The backends part 2's table times, in its column order.
pub fn timed_backends() -> Vec<Backend> {
    [Backend::Native, Backend::Embree, Backend::None]
        .into_iter()
        .filter(|b| b.available())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scenes() -> Scenes {
        Scenes::given(&[PathBuf::from("a.dae"), PathBuf::from("b.dae")])
    }

    #[test]
    fn every_part_is_planned_and_files_are_unique() {
        let sections = plan(&scenes(), &Budget::quick(), 0);
        let ids: Vec<&str> = sections.iter().map(|s| s.id).collect();
        assert_eq!(ids, ["part1", "part2", "part3", "part4", "part5", "part6"]);
        let mut files: Vec<String> = Vec::new();
        for s in &sections {
            for item in &s.items {
                if let Planned::Figures { shots, .. } = item {
                    files.extend(shots.iter().map(|s| s.file.clone()));
                }
            }
        }
        let n = files.len();
        files.sort();
        files.dedup();
        assert_eq!(files.len(), n, "two figures share a file");
        // Part 3: 2 scenes × 2 strategies × 4 -l; part 4: 3 + 6 + 6 + 4.
        assert_eq!(n, 2 + 2 + 16 + 19 + 2);
    }
}
