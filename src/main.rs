//! The `sylva` command line. Each subcommand lives in `src/cli/<area>.rs`; this file only
//! dispatches. Errors from the library are reported once here, with their chain of causes.

mod cli;

use clap::{Parser, Subcommand};

/// Sylva: forests at terrain scale.
#[derive(Parser)]
#[command(name = "sylva", version, about, long_about = None)]
struct Cli {
    /// More log output (-v info, -vv debug); RUST_LOG overrides.
    #[arg(short, long, action = clap::ArgAction::Count, global = true)]
    verbose: u8,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run the main job: afforest a landscape, write maps, inventories, stills and a timelapse.
    Run(cli::run::Args),
    /// Elevation models: information and condition maps.
    #[command(subcommand)]
    Terrain(cli::terrain::Command),
    /// The species library: list, show, check, new.
    #[command(subcommand)]
    Species(cli::species::Command),
    /// Run an ecosystem simulation from a scenario file.
    Simulate(cli::simulate::Args),
    /// Single trees: grow a skeleton and export meshes.
    #[command(subcommand)]
    Tree(cli::tree::Command),
    /// Render a still of a simulation run.
    Render(cli::render::RenderArgs),
    /// Render a timelapse of a simulation run.
    Timelapse(cli::render::TimelapseArgs),
    /// Export the adapted trees of an area, the terrain and obstacles as one glTF scene.
    Export(cli::export::Args),
    /// Open a run directory in the interactive viewer (years, cameras, overlays, trees, stand table).
    View(cli::view::ViewArgs),
    /// Edit a species file with sliders, curves, a live tree preview and validation.
    Edit(cli::view::EditArgs),
}

fn main() -> std::process::ExitCode {
    // `sylva terrain info … | head`: a closed pipe ends the program quietly, as for other tools
    // (Rust ignores SIGPIPE by default, and `println!` would then panic on EPIPE).
    #[cfg(unix)]
    // SAFETY: called first thing on the main thread, before any other thread exists.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    let cli = Cli::parse();
    cli::init_logging(cli.verbose);
    // commands without a stop flag of their own: a stop clears the file being written
    if matches!(cli.command, Command::Export(_) | Command::Render(_) | Command::Timelapse(_) | Command::Tree(_) | Command::Terrain(_)) {
        // a timelapse's finished frames are whole files and stay (trial 47 D10: the message
        // said nothing was left)
        let kept = if matches!(cli.command, Command::Timelapse(_)) { "; the film's finished frames stay in the `frames/` folder beside --out" } else { "" };
        let _ = ctrlc::set_handler(move || {
            sylva::output::remove_pending_temporaries();
            eprintln!("stopped (Ctrl-C or SIGTERM): nothing half-written is left{kept}");
            std::process::exit(130);
        });
    }
    let res = match cli.command {
        Command::Run(a) => cli::run::run(a),
        Command::Terrain(c) => cli::terrain::run(c),
        Command::Species(c) => cli::species::run(c),
        Command::Simulate(a) => cli::simulate::run(a),
        Command::Tree(c) => cli::tree::run(c),
        Command::Render(a) => cli::render::render(a),
        Command::Timelapse(a) => cli::render::timelapse(a),
        Command::Export(a) => cli::export::run(a),
        Command::View(a) => cli::view::view(a),
        Command::Edit(a) => cli::view::edit(a),
    };
    match res {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) if e.is::<cli::Interrupted>() => {
            eprintln!("{e}");
            std::process::ExitCode::from(130)
        }
        Err(e) => {
            eprintln!("error: {e}");
            // causes whose text the message above already contains are not repeated
            let mut said = e.to_string();
            for cause in e.chain().skip(1) {
                let c = cause.to_string();
                if !said.contains(&c) {
                    eprintln!("  caused by: {c}");
                    said.push_str(&c);
                }
            }
            std::process::ExitCode::FAILURE
        }
    }
}
