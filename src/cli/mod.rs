//! The `ember` command line in three layers, as ripgrep splits its flags: `args`
//! defines the flags, `convert` turns them into library settings, and `commands` has
//! one short function per subcommand. Nothing in the library depends on this module.

mod args;
#[cfg(feature = "bench")]
mod bench;
mod commands;
mod convert;

pub use args::Cli;
use args::Command;

pub fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Some(Command::Info { scene, resolution }) => {
            commands::info(&scene, resolution[0], resolution[1])
        }
        Some(Command::Export(args)) => commands::export(args),
        Some(Command::Merge { out, parts }) => commands::merge(&out, &parts),
        Some(Command::Camera(args)) => commands::camera(args),
        #[cfg(feature = "bench")]
        Some(Command::Bench { which }) => bench::run(which),
        None => commands::render(cli.render),
    }
}
