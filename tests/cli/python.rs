//! The Python package (`python/`): builds it with maturin into a virtual
//! environment in the target directory (`target/pyenv`, made once; pip
//! needs PyPI the first time) and runs its pytest suite (`python/tests`),
//! which compares Python episodes with this binary's.

use std::path::{Path, PathBuf};
use std::process::Command;

/// What the package's tests need besides the package (its own
/// dependencies, numpy and gymnasium, come with it).
const TEST_REQUIREMENTS: [&str; 3] = ["maturin>=1.7,<2", "pytest>=7", "gymnasium>=1.0,<1.3"];

fn target_dir() -> PathBuf {
    std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../target"))
}

fn run(command: &mut Command, what: &str) {
    let status = command
        .status()
        .unwrap_or_else(|e| panic!("{what}: cannot start it: {e}"));
    assert!(status.success(), "{what} failed ({status})");
}

#[test]
fn python_package_passes_its_pytest_suite() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    if Command::new("python3").arg("--version").output().is_err() {
        println!("skipped: no python3 on PATH (the Python package needs Python 3.10+)");
        return;
    }
    let venv = target_dir().join("pyenv");
    let bin = venv.join("bin");
    if !bin.join("python").exists() {
        run(
            Command::new("python3").args(["-m", "venv"]).arg(&venv),
            "python3 -m venv",
        );
    }
    let path = format!(
        "{}:{}",
        bin.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    run(
        Command::new(bin.join("python"))
            .args(["-m", "pip", "install", "--quiet"])
            .args(TEST_REQUIREMENTS),
        "pip install the test requirements",
    );
    // The extension is built in the workspace's target directory with the
    // dev profile, whose optimised dependencies it shares where their
    // features agree (cargo releases the directory once the tests are built).
    run(
        Command::new(bin.join("python"))
            .args(["-m", "pip", "install", "--quiet", "--no-build-isolation"])
            .arg("--config-settings=build-args=--profile=dev")
            .arg(root.join("python"))
            .env("PATH", &path)
            .env("CARGO_TARGET_DIR", target_dir()),
        "pip install ./python",
    );
    run(
        Command::new(bin.join("python"))
            .args(["-m", "pytest", "-q"])
            .arg(root.join("python/tests"))
            .env("PATH", &path)
            .env("QUADWALK_BIN", env!("CARGO_BIN_EXE_quadwalk"))
            .current_dir(&root),
        "pytest python/tests",
    );
}
