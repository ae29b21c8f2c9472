//! Checkpoints, what every algorithm's share: a directory holding
//!
//! | file | content |
//! | --- | --- |
//! | `weights.safetensors` | the networks, the normaliser (`obs_norm.mean`, `obs_norm.var`, f64) and the optimisers' moments (`adam.m.NAME`, `adam.v.NAME`) |
//! | `state.toml` | format version, the algorithm's format (`algo`; absent: PPO), iteration, seed, sizes, the sampling RNG's position, the learner's settings, and the FNV-1a 64 checksum of `weights.safetensors` |
//! | anything the caller adds | (the CLI adds `config.toml`, the resolved experiment) |
//!
//! Writing is atomic: the files go into a hidden sibling directory, are
//! flushed to disk, and the directory is renamed into place in one step; a
//! process killed during a save leaves at most a stray hidden directory,
//! never a half-written checkpoint. The run directory's `latest` is a
//! symbolic link replaced by rename, so it always names a complete one.
//! Loading checks the checksum, every tensor's presence and shape, and
//! every value's range, and says which file and which entry is wrong.

use std::collections::HashMap;
use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};

use candle_core::{DType, Device, Tensor, Var};
use safetensors::SafeTensors;
use serde::Serialize;

use crate::LearnError;
use crate::normalizer::ObsNormalizer;
use crate::optim::Adam;
use crate::seeds::RngState;

/// The weights file's name.
pub const WEIGHTS_FILE: &str = "weights.safetensors";
/// The state file's name.
pub const STATE_FILE: &str = "state.toml";
/// The link to the newest checkpoint inside a run directory.
pub const LATEST_LINK: &str = "latest";
/// Version of the layout above.
pub const FORMAT_VERSION: u32 = 1;
/// Test hook: when set to a number of milliseconds, a save sleeps that long
/// after writing its first file (so that a test can kill the process in the
/// middle of a save).
pub const SAVE_PAUSE_ENV: &str = "QUADWALK_TEST_SAVE_PAUSE_MS";

/// FNV-1a, 64 bit.
pub fn fnv1a64(bytes: &[u8]) -> u64 {
    let mut hash = 0xcbf2_9ce4_8422_2325u64;
    for &b in bytes {
        hash ^= u64::from(b);
        hash = hash.wrapping_mul(0x0100_0000_01b3);
    }
    hash
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

fn unhex32(text: &str) -> Option<[u8; 32]> {
    if text.len() != 64 {
        return None;
    }
    let mut out = [0u8; 32];
    for (k, byte) in out.iter_mut().enumerate() {
        *byte = u8::from_str_radix(text.get(2 * k..2 * k + 2)?, 16).ok()?;
    }
    Some(out)
}

/// A checkpoint file's path and what is wrong with it, as an error.
pub(crate) fn bad_file(dir: &Path, file: &str, what: String) -> LearnError {
    LearnError::Checkpoint(format!("{}: {what}", dir.join(file).display()))
}

/// Reads and parses `dir/state.toml`.
pub(crate) fn read_state<T: serde::de::DeserializeOwned>(dir: &Path) -> Result<T, LearnError> {
    let text = fs::read_to_string(dir.join(STATE_FILE))
        .map_err(|e| bad_file(dir, STATE_FILE, format!("cannot read it: {e}")))?;
    toml::from_str(&text).map_err(|e| {
        bad_file(
            dir,
            STATE_FILE,
            format!("not a valid state file: {}", e.message()),
        )
    })
}

/// Serialises `value` as a state file.
pub(crate) fn state_text<T: Serialize>(value: &T) -> Result<Vec<u8>, LearnError> {
    toml::to_string(value)
        .map(String::into_bytes)
        .map_err(|e| LearnError::Checkpoint(format!("cannot serialise the state: {e}")))
}

/// Serialises named tensors as a safetensors file.
pub(crate) fn tensors_file(tensors: Vec<(String, Tensor)>) -> Result<Vec<u8>, LearnError> {
    safetensors::serialize(tensors, None)
        .map_err(|e| LearnError::Checkpoint(format!("cannot serialise the weights: {e}")))
}

/// Reads `dir/file` and checks it against the FNV-1a 64 checksum (hex) that
/// `recorded_in` (the state file, or an exported policy's description)
/// recorded.
pub(crate) fn read_checksummed(
    dir: &Path,
    file: &str,
    recorded_in: &str,
    recorded_hex: &str,
) -> Result<Vec<u8>, LearnError> {
    let bytes = fs::read(dir.join(file))
        .map_err(|e| bad_file(dir, file, format!("cannot read it: {e}")))?;
    let checksum = format!("{:016x}", fnv1a64(&bytes));
    if checksum != recorded_hex {
        return Err(bad_file(
            dir,
            file,
            format!(
                "checksum {checksum} differs from {recorded_hex} recorded in {recorded_in}: the file is damaged or truncated"
            ),
        ));
    }
    Ok(bytes)
}

/// Shape-, type- and value-checked access to the tensors of a checkpoint's
/// safetensors file.
pub(crate) struct TensorFile<'a> {
    tensors: SafeTensors<'a>,
    dir: &'a Path,
    file: &'a str,
}

impl<'a> TensorFile<'a> {
    /// Parses `bytes`, read from `dir/file`.
    pub(crate) fn parse(bytes: &'a [u8], dir: &'a Path, file: &'a str) -> Result<Self, LearnError> {
        let tensors = SafeTensors::deserialize(bytes)
            .map_err(|e| bad_file(dir, file, format!("not a safetensors file: {e}")))?;
        Ok(Self { tensors, dir, file })
    }

    /// The tensor `name`, which must have `shape` and `dtype`.
    pub(crate) fn get(
        &self,
        name: &str,
        shape: &[usize],
        dtype: DType,
    ) -> Result<Tensor, LearnError> {
        let bad = |what: String| bad_file(self.dir, self.file, what);
        let view = self
            .tensors
            .tensor(name)
            .map_err(|_| bad(format!("tensor {name:?} is missing")))?;
        if view.shape() != shape {
            return Err(bad(format!(
                "tensor {name:?} has shape {:?}, the configuration needs {shape:?}",
                view.shape()
            )));
        }
        let tensor = candle_core::safetensors::Load::load(&view, &Device::Cpu)?;
        if tensor.dtype() != dtype {
            return Err(bad(format!(
                "tensor {name:?} is {:?}, expected {dtype:?}",
                tensor.dtype()
            )));
        }
        Ok(tensor)
    }

    /// [`Self::get`] for an `f32` tensor whose values must all be finite.
    pub(crate) fn get_finite(&self, name: &str, shape: &[usize]) -> Result<Tensor, LearnError> {
        let t = self.get(name, shape, DType::F32)?;
        let values: Vec<f32> = t.flatten_all()?.to_vec1()?;
        if values.iter().all(|v| v.is_finite()) {
            Ok(t)
        } else {
            Err(bad_file(
                self.dir,
                self.file,
                format!("tensor {name:?} holds a non-finite value"),
            ))
        }
    }

    /// Loads every var of `vars` (shapes from the vars themselves).
    pub(crate) fn load_vars(&self, vars: &[(String, Var)]) -> Result<(), LearnError> {
        for (name, var) in vars {
            var.set(&self.get_finite(name, var.as_tensor().dims())?)?;
        }
        Ok(())
    }

    /// Loads Adam's moments (`<prefix>.m.NAME`, `<prefix>.v.NAME`) and sets its step.
    pub(crate) fn load_adam(
        &self,
        adam: &mut Adam,
        prefix: &str,
        step: u64,
    ) -> Result<(), LearnError> {
        adam.step = step;
        let names: Vec<(String, Var)> = adam.vars().to_vec();
        for (k, (name, var)) in names.iter().enumerate() {
            let dims = var.as_tensor().dims();
            adam.m[k] = self.get_finite(&format!("{prefix}.m.{name}"), dims)?;
            adam.v[k] = self.get_finite(&format!("{prefix}.v.{name}"), dims)?;
        }
        Ok(())
    }

    /// The observation normaliser saved as `obs_norm.mean` / `obs_norm.var`.
    pub(crate) fn load_normalizer(
        &self,
        size: usize,
        count: f64,
        clip: f64,
    ) -> Result<ObsNormalizer, LearnError> {
        let mean: Vec<f64> = self.get("obs_norm.mean", &[size], DType::F64)?.to_vec1()?;
        let var: Vec<f64> = self.get("obs_norm.var", &[size], DType::F64)?.to_vec1()?;
        ObsNormalizer::from_parts(mean, var, count, clip)
            .map_err(|e| bad_file(self.dir, self.file, e.to_string()))
    }
}

/// Vars as named tensors (their current values).
pub(crate) fn var_tensors(vars: Vec<(String, Var)>) -> Vec<(String, Tensor)> {
    vars.into_iter()
        .map(|(name, var)| (name, var.as_tensor().clone()))
        .collect()
}

/// Adam's moments as named tensors `<prefix>.m.NAME`, `<prefix>.v.NAME`.
pub(crate) fn adam_tensors(adam: &Adam, prefix: &str) -> Vec<(String, Tensor)> {
    adam.vars()
        .iter()
        .enumerate()
        .flat_map(|(k, (name, _))| {
            [
                (format!("{prefix}.m.{name}"), adam.m[k].clone()),
                (format!("{prefix}.v.{name}"), adam.v[k].clone()),
            ]
        })
        .collect()
}

/// The normaliser as named tensors `obs_norm.mean`, `obs_norm.var` (f64).
pub(crate) fn normalizer_tensors(n: &ObsNormalizer) -> Result<Vec<(String, Tensor)>, LearnError> {
    let device = Device::Cpu;
    Ok(vec![
        (
            "obs_norm.mean".into(),
            Tensor::from_slice(&n.mean, n.size(), &device)?,
        ),
        (
            "obs_norm.var".into(),
            Tensor::from_slice(&n.var, n.size(), &device)?,
        ),
    ])
}

/// A generator's position as the state file records it: (seed hex, stream,
/// word position as decimal text).
pub(crate) fn rng_fields(rng: &RngState) -> (String, u64, String) {
    (hex(&rng.seed), rng.stream, rng.word_pos.to_string())
}

/// The generator position recorded by [`rng_fields`].
pub(crate) fn rng_from_fields(
    dir: &Path,
    seed_hex: &str,
    stream: u64,
    word_pos: &str,
) -> Result<RngState, LearnError> {
    let seed = unhex32(seed_hex)
        .ok_or_else(|| bad_file(dir, STATE_FILE, "rng_seed_hex is not 64 hex digits".into()))?;
    let word_pos: u128 = word_pos.parse().map_err(|_| {
        bad_file(
            dir,
            STATE_FILE,
            format!("rng_word_pos {word_pos:?} is not a number"),
        )
    })?;
    Ok(RngState {
        seed,
        stream,
        word_pos,
    })
}

/// The checkpoint directory that `path` means: itself when it holds a
/// state file, else its `latest`. An exported policy is refused, naming it.
pub fn resolve_checkpoint(path: &Path) -> Result<PathBuf, LearnError> {
    if crate::export::is_exported_policy(path) {
        return Err(crate::export::not_a_checkpoint(path));
    }
    if path.join(STATE_FILE).is_file() {
        return Ok(path.to_path_buf());
    }
    let latest = path.join(LATEST_LINK);
    if latest.join(STATE_FILE).is_file() {
        return Ok(latest);
    }
    if !path.exists() {
        return Err(LearnError::Checkpoint(format!(
            "{}: no such file or directory",
            path.display()
        )));
    }
    Err(LearnError::Checkpoint(format!(
        "{}: not a checkpoint (no {STATE_FILE}) nor a run directory with a `{LATEST_LINK}` checkpoint",
        path.display()
    )))
}

/// Creates `path` holding `bytes`, flushed to disk.
fn write_synced(path: &Path, bytes: &[u8]) -> Result<(), LearnError> {
    let io = |what: &str, e: std::io::Error| {
        LearnError::Checkpoint(format!("{}: cannot {what}: {e}", path.display()))
    };
    let mut f = fs::File::create(path).map_err(|e| io("create", e))?;
    f.write_all(bytes).map_err(|e| io("write", e))?;
    f.sync_all().map_err(|e| io("flush", e))
}

/// Writes one file atomically: into a hidden sibling `.NAME.partial-PID`
/// (which [`remove_partial_saves`] clears if a kill leaves it), flushed, then
/// renamed over `path`.
pub fn write_file_atomically(path: &Path, bytes: &[u8]) -> Result<(), LearnError> {
    let name = path
        .file_name()
        .ok_or_else(|| LearnError::Checkpoint(format!("{}: not a file name", path.display())))?;
    let staging = path.with_file_name(format!(
        ".{}.partial-{}",
        name.to_string_lossy(),
        std::process::id()
    ));
    write_synced(&staging, bytes)?;
    fs::rename(&staging, path)
        .map_err(|e| LearnError::Checkpoint(format!("{}: cannot replace it: {e}", path.display())))
}

/// Writes `files` into directory `target` atomically (see the module docs).
/// A `target` that already exists is left as it is (checkpoints are named
/// by iteration, so it holds the same content).
pub fn write_dir_atomically(target: &Path, files: &[(String, Vec<u8>)]) -> Result<(), LearnError> {
    let io = |what: &str, path: &Path, e: std::io::Error| {
        LearnError::Checkpoint(format!("{}: cannot {what}: {e}", path.display()))
    };
    if target.join(STATE_FILE).is_file() {
        return Ok(());
    }
    let parent = target
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let name = target.file_name().ok_or_else(|| {
        LearnError::Checkpoint(format!("{}: not a directory name", target.display()))
    })?;
    fs::create_dir_all(parent).map_err(|e| io("create the directory", parent, e))?;
    let staging = parent.join(format!(
        ".{}.partial-{}",
        name.to_string_lossy(),
        std::process::id()
    ));
    if staging.exists() {
        fs::remove_dir_all(&staging).map_err(|e| io("remove", &staging, e))?;
    }
    fs::create_dir(&staging).map_err(|e| io("create", &staging, e))?;
    let pause_ms: Option<u64> = std::env::var(SAVE_PAUSE_ENV)
        .ok()
        .and_then(|v| v.parse().ok());
    for (k, (file, bytes)) in files.iter().enumerate() {
        let path = staging.join(file);
        if let Some(dir) = path.parent().filter(|d| *d != staging) {
            fs::create_dir_all(dir).map_err(|e| io("create the directory", dir, e))?;
        }
        write_synced(&path, bytes)?;
        if k == 0
            && let Some(ms) = pause_ms
        {
            std::thread::sleep(std::time::Duration::from_millis(ms));
        }
    }
    sync_dir(&staging);
    if target.exists() {
        // an incomplete directory of that name (not ours): replace it
        fs::remove_dir_all(target).map_err(|e| io("remove", target, e))?;
    }
    fs::rename(&staging, target)
        .map_err(|e| io("move the new checkpoint into place at", target, e))?;
    sync_dir(parent);
    Ok(())
}

/// Points `run_dir/latest` at `checkpoint` (a path relative to `run_dir`),
/// atomically.
pub fn point_latest(run_dir: &Path, checkpoint: &Path) -> Result<(), LearnError> {
    let link = run_dir.join(LATEST_LINK);
    let staging = run_dir.join(format!(".{LATEST_LINK}.partial-{}", std::process::id()));
    let _ = fs::remove_file(&staging);
    #[cfg(unix)]
    std::os::unix::fs::symlink(checkpoint, &staging).map_err(|e| {
        LearnError::Checkpoint(format!(
            "{}: cannot create the link: {e}",
            staging.display()
        ))
    })?;
    #[cfg(not(unix))]
    return Err(LearnError::Checkpoint(format!(
        "{}: the `latest` link needs a Unix file system",
        link.display()
    )));
    #[cfg(unix)]
    {
        fs::rename(&staging, &link).map_err(|e| {
            LearnError::Checkpoint(format!("{}: cannot replace the link: {e}", link.display()))
        })?;
        sync_dir(run_dir);
        Ok(())
    }
}

/// Removes the stray staging directories a killed save may have left.
pub fn remove_partial_saves(dir: &Path) {
    if let Ok(entries) = fs::read_dir(dir) {
        for entry in entries.flatten() {
            let name = entry.file_name().to_string_lossy().to_string();
            if name.starts_with('.') && name.contains(".partial-") {
                let path = entry.path();
                let _ = if path.is_dir() {
                    fs::remove_dir_all(&path)
                } else {
                    fs::remove_file(&path)
                };
            }
        }
    }
}

fn sync_dir(dir: &Path) {
    // Best effort: some file systems refuse to fsync a directory.
    if let Ok(d) = fs::File::open(dir) {
        let _ = d.sync_all();
    }
}

/// The tensors of a safetensors file, by name (for tools and tests).
pub fn read_tensors(path: &Path) -> Result<HashMap<String, Tensor>, LearnError> {
    candle_core::safetensors::load(path, &Device::Cpu)
        .map_err(|e| LearnError::Checkpoint(format!("{}: {e}", path.display())))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn single_files_are_replaced_whole() {
        let tmp = tempfile::tempdir().unwrap();
        let path = tmp.path().join("config.toml");
        write_file_atomically(&path, b"first").unwrap();
        write_file_atomically(&path, b"second").unwrap();
        assert_eq!(fs::read(&path).unwrap(), b"second");
        let names: Vec<String> = fs::read_dir(tmp.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
            .collect();
        assert_eq!(names, ["config.toml"], "no staging file is left");
    }
}
