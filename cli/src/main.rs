//! `quadwalk`: learn quadruped locomotion on ground that gives way.
//!
//! The command line lives in the `quadwalk_cli` library; this binary runs it
//! with the built-in terrain plugins. A binary of your own registers more
//! (see `examples/terrain-plugin`).

use std::process::ExitCode;

fn main() -> ExitCode {
    quadwalk_cli::App::new().on_second_interrupt(stop_now).run()
}

/// A second Ctrl-C during training: stop at once (the last checkpoint
/// stands), with the shell's code for an interrupt.
fn stop_now() -> ! {
    std::process::exit(130)
}
