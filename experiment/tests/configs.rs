//! Every experiment file in `configs/` reads, and every one whose header
//! says it forks a shipped policy's checkpoint trains that policy's
//! iterations exactly as its run did (what `quadwalk train --fork` checks
//! before it starts).

use std::path::{Path, PathBuf};

use experiment::config::Experiment;
use terrain_plugins::Registry;

fn repository() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn configs() -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(repository().join("configs"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    assert!(files.len() > 10, "{files:?}");
    files
}

#[test]
fn every_config_reads() {
    let registry = Registry::builtin();
    for path in configs() {
        if let Err(e) = Experiment::from_file(&path, &registry) {
            panic!("{}: {e:#}", path.display());
        }
    }
}

#[test]
fn every_fork_of_a_shipped_policy_trains_its_iterations_as_it_did() {
    let registry = Registry::builtin();
    let mut forks = 0;
    for path in configs() {
        let text = std::fs::read_to_string(&path).unwrap();
        // `--fork policies/NAME/checkpoint` in the header's command
        let Some(at) = text.find("--fork policies/") else {
            continue;
        };
        let rest = &text[at + "--fork ".len()..];
        let policy = rest.split_whitespace().next().unwrap();
        let policy_dir = repository().join(policy.trim_end_matches("/checkpoint"));
        let shipped = Experiment::from_file(&policy_dir.join("config.toml"), &registry).unwrap();
        let fork = Experiment::from_file(&path, &registry).unwrap();
        let iterations = shipped.total_iterations();
        assert!(
            fork.total_iterations() > iterations,
            "{}: trains nothing past {policy}",
            path.display()
        );
        if let Some(difference) = fork.differs_before(&shipped, iterations) {
            panic!(
                "{} does not train {policy}'s {iterations} iterations as its run did: {difference}",
                path.display()
            );
        }
        forks += 1;
    }
    assert!(forks >= 5, "{forks} forks found");
}
