//! Runs the Python package's pytest suite (`python/tests/test_*.py`).
//!
//! `cargo test` builds this crate's extension module (`deps/lib_quadwalk.so`,
//! with the `extension-module` feature on by default) beside the workspace's
//! other artefacts, with the same dependencies, so no second build of the
//! dependency tree is needed (maturin's `pip install ./python` makes one,
//! for users). This test lays the package out in the target directory
//! (`target/python-package/quadwalk`: `pysrc/quadwalk` and the module as
//! `_quadwalk.abi3.so`), makes a virtual environment there once
//! (`target/pyenv`), installs what the tests import (numpy, gymnasium,
//! pytest, for the trainer tests torch, Stable-Baselines3 and Ray RLlib, and
//! for the ONNX and second-engine tests onnx, onnxruntime and mujoco;
//! pip needs PyPI the first time) and runs pytest against the `quadwalk`
//! binary built by the same `cargo test --workspace`.
//!
//! Skipped, with the reason printed, where there is no `python3`.

use std::path::{Path, PathBuf};
use std::process::Command;

/// What the tests import besides the package: its own dependencies, the
/// trainers and ONNX (`pyproject.toml`'s `test`, `sb3`, `rllib` and `onnx`
/// extras, and `mujoco` for the second engine).
/// RLlib 2.5x pins gymnasium 1.2.x; the package accepts 1.0 to 1.4.
const TEST_REQUIREMENTS: [&str; 9] = [
    "numpy>=1.23",
    "gymnasium>=1.0,<1.3",
    "pytest>=7",
    "stable-baselines3>=2.3,<3",
    "ray[rllib]>=2.50,<3",
    "torch>=2.3,<3",
    "onnx>=1.15,<2",
    "onnxruntime>=1.17,<2",
    "mujoco>=3.2,<4",
];

/// The directory that holds this test's executable, `target/<profile>/deps`,
/// where cargo also leaves the crate's cdylib (not copied up to
/// `target/<profile>`, as it is built for this test, not asked for).
fn deps_dir() -> PathBuf {
    let exe = std::env::current_exe().expect("the test executable's path");
    exe.parent()
        .map(Path::to_path_buf)
        .expect("the test executable lies in <target>/<profile>/deps")
}

fn run(command: &mut Command, what: &str) {
    let status = command
        .status()
        .unwrap_or_else(|e| panic!("{what}: cannot start it: {e}"));
    assert!(status.success(), "{what} failed ({status})");
}

/// Copies the package's Python sources and the freshly built module into
/// `dir/quadwalk` (replacing what an earlier run left there).
fn lay_out_package(source: &Path, module: &Path, dir: &Path) {
    let package = dir.join("quadwalk");
    if package.exists() {
        std::fs::remove_dir_all(&package).expect("remove the old package copy");
    }
    std::fs::create_dir_all(&package).expect("create target/python-package/quadwalk");
    for entry in std::fs::read_dir(source).expect("read python/pysrc/quadwalk") {
        let path = entry.expect("a directory entry").path();
        if path.extension().is_some_and(|e| e == "py" || e == "typed") {
            std::fs::copy(&path, package.join(path.file_name().unwrap()))
                .unwrap_or_else(|e| panic!("copy {}: {e}", path.display()));
        }
    }
    std::fs::copy(module, package.join("_quadwalk.abi3.so"))
        .unwrap_or_else(|e| panic!("copy {}: {e}", module.display()));
}

#[test]
fn python_package_passes_its_pytest_suite() {
    if Command::new("python3").arg("--version").output().is_err() {
        println!("skipped: no python3 on PATH (the Python package needs Python 3.10+)");
        return;
    }
    let crate_dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let deps = deps_dir();
    let profile = deps.parent().expect("<target>/<profile>").to_path_buf();
    let target = profile.parent().expect("<target>").to_path_buf();
    let module = deps.join(format!(
        "{}_quadwalk{}",
        std::env::consts::DLL_PREFIX,
        std::env::consts::DLL_SUFFIX
    ));
    assert!(
        module.is_file(),
        "{} is missing: cargo test builds it with this crate",
        module.display()
    );
    let binary = profile.join(format!("quadwalk{}", std::env::consts::EXE_SUFFIX));
    assert!(
        binary.is_file(),
        "{} is missing: run the suite with `cargo test --workspace`, which builds the \
         quadwalk binary the Python episodes are compared with",
        binary.display()
    );
    let package_dir = target.join("python-package");
    lay_out_package(&crate_dir.join("pysrc/quadwalk"), &module, &package_dir);

    let venv = target.join("pyenv");
    let python = venv.join("bin/python");
    if !python.exists() {
        run(
            Command::new("python3").args(["-m", "venv"]).arg(&venv),
            "python3 -m venv",
        );
    }
    run(
        Command::new(&python)
            // no wheel cache: torch's wheels would take as much disk again
            .args(["-m", "pip", "install", "--quiet", "--no-cache-dir"])
            .args(TEST_REQUIREMENTS),
        "pip install the test requirements",
    );
    let path = format!(
        "{}:{}",
        venv.join("bin").display(),
        std::env::var("PATH").unwrap_or_default()
    );
    run(
        Command::new(&python)
            .args(["-m", "pytest", "-q", "-p", "no:cacheprovider"])
            .arg(crate_dir.join("tests"))
            .env("PATH", &path)
            .env("PYTHONPATH", &package_dir)
            .env("QUADWALK_BIN", &binary)
            .current_dir(crate_dir.join("..")),
        "pytest python/tests",
    );
}
