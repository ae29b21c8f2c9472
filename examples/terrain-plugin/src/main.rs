//! `quadwalk-pontoon`: every quadwalk command, with the pontoon terrain too.

use std::process::ExitCode;

fn main() -> ExitCode {
    quadwalk_cli::App::new() // the built-in terrains
        .add_terrain(Box::new(quadwalk_pontoon::PontoonPlugin)) // and ours
        .on_second_interrupt(|| std::process::exit(130)) // a second Ctrl-C stops training at once
        .run()
}
