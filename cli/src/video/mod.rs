//! `--video FILE.gif` on `rollout`, `play` and `eval`: an animation of a run
//! drawn on the CPU, without a GPU or a display (a server, CI, a cluster
//! node), frame by frame as the run goes, straight into the file.
//!
//! A frame is taken every round(rate / fps) physics steps (at the paper's
//! 240 Hz the default 30 fps is every 8th step) and once before the
//! first step; its content is in `draw.rs`. GIF delays are whole
//! hundredths of a second, so frame k is shown from round(100 k / fps) to
//! round(100 (k + 1) / fps) cs: the animation plays in real time on
//! average. MP4 is not written: no maintained pure-Rust H.264 encoder fits
//! the build.

mod draw;
mod gif_file;

use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::{Result, bail};
use clap::Args;
use nalgebra::Vector3;
use robot::RobotModel;
use robot::model::LegName;
use robot::snapshot::{PhaseObserver, PhaseStart};
use robot::task::{PhaseOutcome, Task};
use terrain_plugins::{Rect, TileState};

use gif_file::GifWriter;

/// A frame's size, pixels.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FrameSize {
    /// width
    pub width_px: u32,
    /// height
    pub height_px: u32,
}

/// The smallest frame that holds both views, the caption and the scale.
const MIN_SIZE_PX: (u32, u32) = (320, 240);
/// The largest frame written.
const MAX_SIZE_PX: (u32, u32) = (3840, 2160);

/// Parses `WIDTHxHEIGHT` (pixels).
fn parse_size(text: &str) -> Result<FrameSize, String> {
    let bad = || {
        format!(
            "{text:?} is not a frame size: give WIDTHxHEIGHT in pixels, from {}x{} to {}x{} (e.g. 640x480)",
            MIN_SIZE_PX.0, MIN_SIZE_PX.1, MAX_SIZE_PX.0, MAX_SIZE_PX.1
        )
    };
    let (w, h) = text.split_once(['x', 'X']).ok_or_else(bad)?;
    let (w, h): (u32, u32) = (
        w.trim().parse().map_err(|_| bad())?,
        h.trim().parse().map_err(|_| bad())?,
    );
    if !(MIN_SIZE_PX.0..=MAX_SIZE_PX.0).contains(&w)
        || !(MIN_SIZE_PX.1..=MAX_SIZE_PX.1).contains(&h)
    {
        return Err(bad());
    }
    Ok(FrameSize {
        width_px: w,
        height_px: h,
    })
}

/// The `--video` flags.
#[derive(Debug, Clone, Args)]
pub struct VideoArgs {
    /// Write an animation of the run to this GIF file (eval: its first
    /// episode): side and top views of the robot, the tiles coloured by
    /// sink, the swing foot's target, the base's path and a caption, drawn
    /// without a GPU or display
    #[arg(long, value_name = "FILE.gif")]
    pub video: Option<PathBuf>,
    /// Frames per second of simulated time (a frame every round(rate / fps)
    /// physics steps, 240 Hz unless the policy trained at another rate)
    #[arg(long, default_value_t = 30, value_parser = clap::value_parser!(u32).range(1..=240), requires = "video")]
    pub video_fps: u32,
    /// Frame size, pixels: WIDTHxHEIGHT
    #[arg(long, default_value = "640x480", value_parser = parse_size, requires = "video")]
    pub video_size: FrameSize,
}

impl VideoArgs {
    /// Checks the file can be written before a run starts: a `.gif` name in
    /// an existing directory.
    pub fn check(&self) -> Result<()> {
        let Some(path) = &self.video else {
            return Ok(());
        };
        let is_gif = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("gif"));
        if !is_gif {
            bail!(
                "--video {}: only GIF animations are written; give a file name ending in .gif",
                path.display()
            );
        }
        let dir = path
            .parent()
            .filter(|d| !d.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        if !dir.is_dir() {
            bail!(
                "--video {}: the directory {} does not exist",
                path.display(),
                dir.display()
            );
        }
        if path.is_dir() {
            bail!("--video {}: is a directory", path.display());
        }
        Ok(())
    }

    /// The recorder for a run, when `--video` was given; `label` names the
    /// run in the caption.
    /// `dt_secs` is the world's physics step.
    pub fn recorder(
        &self,
        model: Arc<RobotModel>,
        label: &str,
        dt_secs: f64,
    ) -> Result<Option<VideoRecorder>> {
        let Some(path) = &self.video else {
            return Ok(None);
        };
        self.check()?;
        VideoRecorder::create(path, self.video_fps, self.video_size, model, label, dt_secs)
            .map(Some)
    }
}

/// What a finished video holds.
#[derive(Debug, Clone, PartialEq)]
pub struct VideoSummary {
    /// the file
    pub path: PathBuf,
    /// frames written
    pub frames: usize,
    /// physics steps between frames
    pub steps_per_frame: u64,
}

/// Draws the run it observes into a GIF file, frame by frame.
pub struct VideoRecorder {
    writer: GifWriter,
    size_px: (u32, u32),
    steps_per_frame: u64,
    fps: f64,
    model: Arc<RobotModel>,
    label: String,
    start_x_m: Option<f64>,
    base_path_m: Vec<Vector3<f64>>,
    swing: Option<(LegName, Vector3<f64>)>,
    steps: u64,
    error: Option<anyhow::Error>,
}

impl VideoRecorder {
    fn create(
        path: &Path,
        fps: u32,
        size: FrameSize,
        model: Arc<RobotModel>,
        label: &str,
        dt_secs: f64,
    ) -> Result<Self> {
        let steps_per_s = 1.0 / dt_secs;
        let steps_per_frame = (steps_per_s / f64::from(fps)).round().max(1.0) as u64;
        let size_px = (size.width_px, size.height_px);
        let writer = GifWriter::create(path, (size.width_px as u16, size.height_px as u16), 0)?;
        Ok(Self {
            writer,
            size_px,
            steps_per_frame,
            fps: steps_per_s / steps_per_frame as f64,
            model,
            label: label.to_string(),
            start_x_m: None,
            base_path_m: Vec::new(),
            swing: None,
            steps: 0,
            error: None,
        })
    }

    /// Draws the task's state now as the next frame (the first one: before
    /// the run's first step).
    pub fn frame(&mut self, task: &Task) {
        if self.error.is_some() {
            return;
        }
        if let Err(e) = self.try_frame(task) {
            self.error = Some(e);
        }
    }

    fn try_frame(&mut self, task: &Task) -> Result<()> {
        let world = task.world();
        let body_poses = world.body_poses();
        let base = body_poses[0].translation.vector;
        let start_x = *self.start_x_m.get_or_insert(base.x);
        if self
            .base_path_m
            .last()
            .is_none_or(|last| (last - base).norm() >= 0.005)
        {
            self.base_path_m.push(base);
        }
        let half_width_m = draw::half_width_shown_m(self.size_px) + 0.2;
        let mut tiles: Vec<TileState> = Vec::new();
        world.terrain().tiles_in(
            world.physics(),
            Rect {
                min_m: [base.x - half_width_m, base.y - half_width_m],
                max_m: [base.x + half_width_m, base.y + half_width_m],
            },
            &mut tiles,
        );
        let samples = 200;
        let ground_profile_m: Vec<(f64, f64)> = (0..=samples)
            .map(|k| {
                let x =
                    base.x - half_width_m + 2.0 * half_width_m * f64::from(k) / f64::from(samples);
                (x, world.surface_height_m(x, base.y))
            })
            .collect();
        let secs = world.time_secs();
        let region = {
            let terrain = world.terrain();
            terrain.regions()[terrain.region_index_at(base.x, base.y)]
                .label
                .clone()
        };
        let caption = format!(
            "t {secs:.2} s | phase {} | {:+.2} m | {region} | {}",
            task.phase(),
            base.x - start_x,
            self.label
        );
        let rgb = draw::draw(
            &draw::FrameState {
                model: &self.model,
                body_poses: &body_poses,
                tiles: &tiles,
                ground_profile_m: &ground_profile_m,
                base_path_m: &self.base_path_m,
                swing: self.swing,
                caption: &caption,
            },
            self.size_px,
        )?;
        // frame k shows from round(100 k / fps) to round(100 (k + 1) / fps) cs
        let k = self.writer.frames() as f64;
        let delay = (100.0 * (k + 1.0) / self.fps).round() - (100.0 * k / self.fps).round();
        self.writer.set_delay_cs(delay.max(1.0) as u16);
        self.writer.push_rgb(&rgb)
    }

    /// Closes the file; the first error met while drawing, if any.
    pub fn finish(self) -> Result<VideoSummary> {
        if let Some(e) = self.error {
            return Err(e);
        }
        Ok(VideoSummary {
            path: self.writer.path().to_path_buf(),
            frames: self.writer.frames(),
            steps_per_frame: self.steps_per_frame,
        })
    }
}

impl PhaseObserver for VideoRecorder {
    fn episode_started(&mut self, task: &Task) {
        self.frame(task);
    }

    fn phase_started(&mut self, _task: &Task, start: &PhaseStart) {
        self.swing = Some((start.swing_leg, start.landing_m()));
    }

    fn stepped(&mut self, task: &Task, _step_in_phase: usize) {
        self.steps += 1;
        if self.steps.is_multiple_of(self.steps_per_frame) {
            self.frame(task);
        }
    }

    fn phase_ended(&mut self, _task: &Task, _outcome: &PhaseOutcome) {}
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_sizes_parse_and_bad_ones_say_what_is_wanted() {
        assert_eq!(
            parse_size("640x480"),
            Ok(FrameSize {
                width_px: 640,
                height_px: 480
            })
        );
        assert_eq!(parse_size("800X600").unwrap().height_px, 600);
        for bad in [
            "640", "x480", "640x", "-640x480", "100x100", "9000x480", "axb",
        ] {
            let err = parse_size(bad).unwrap_err();
            assert!(
                err.contains(bad) && err.contains("WIDTHxHEIGHT"),
                "{bad}: {err}"
            );
        }
    }

    #[test]
    fn a_video_file_must_be_a_gif_in_a_directory_that_exists() {
        let args = |path: &str| VideoArgs {
            video: Some(PathBuf::from(path)),
            video_fps: 30,
            video_size: FrameSize {
                width_px: 640,
                height_px: 480,
            },
        };
        let err = args("out.mp4").check().unwrap_err().to_string();
        assert!(err.contains("out.mp4") && err.contains(".gif"), "{err}");
        let err = args("/no/such/dir/out.gif")
            .check()
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("/no/such/dir") && err.contains("does not exist"),
            "{err}"
        );
        args("out.gif").check().unwrap();
    }
}
