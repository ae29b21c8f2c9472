//! `--video`: a GIF of the run with the expected frames, in which the
//! robot moves; bad paths and sizes are refused before anything runs.

use std::path::Path;

use super::train::{s, scratch_dir};
use super::{failure, json_of};

/// Every frame of a GIF, as RGB pixels, and its size.
fn frames(path: &Path) -> (Vec<Vec<u8>>, (u16, u16)) {
    let mut options = gif::DecodeOptions::new();
    options.set_color_output(gif::ColorOutput::RGBA);
    let mut decoder = options
        .read_info(std::fs::File::open(path).unwrap())
        .unwrap();
    let size = (decoder.width(), decoder.height());
    let mut out = Vec::new();
    while let Some(frame) = decoder.read_next_frame().unwrap() {
        assert_eq!((frame.width, frame.height), size, "full frames");
        out.push(
            frame
                .buffer
                .chunks_exact(4)
                .flat_map(|p| [p[0], p[1], p[2]])
                .collect(),
        );
    }
    (out, size)
}

/// Pixels drawn in the robot's colours (the base's blue, the near legs'
/// dark grey, the swing leg's orange), as the palette keeps them.
fn robot_pixels(frame: &[u8]) -> Vec<usize> {
    frame
        .chunks_exact(3)
        .enumerate()
        .filter(|(_, p)| {
            let (r, g, b) = (i32::from(p[0]), i32::from(p[1]), i32::from(p[2]));
            let near =
                |c: (i32, i32, i32)| (r - c.0).abs() + (g - c.1).abs() + (b - c.2).abs() < 60;
            near((70, 110, 170)) || near((55, 60, 70)) || near((235, 140, 20))
        })
        .map(|(k, _)| k)
        .collect()
}

#[test]
fn rollout_and_eval_write_an_animation_in_which_the_robot_walks() {
    let dir = scratch_dir("video");
    let gif = dir.join("walk.gif");
    let policy = Path::new(env!("CARGO_MANIFEST_DIR")).join("../policies/elastic-5cm");
    let r = json_of(&[
        "rollout",
        "--policy",
        s(&policy),
        "--terrain",
        "elastic:5cm",
        "--phases",
        "2",
        "--video",
        s(&gif),
        "--video-size",
        "320x240",
        "--json",
    ]);
    // a frame before the first step, then one every 8 of 2 x 180 steps
    assert_eq!(r["video"]["frames"], 1 + 2 * 180 / 8, "{r}");
    assert_eq!(r["video"]["steps_per_frame"], 8);
    let (shown, size) = frames(&gif);
    assert_eq!(size, (320, 240));
    assert_eq!(shown.len(), 46);
    let (first, last) = (robot_pixels(&shown[0]), robot_pixels(&shown[45]));
    assert!(
        first.len() > 500,
        "the robot is drawn: {} pixels",
        first.len()
    );
    let moved = first
        .iter()
        .filter(|k| last.binary_search(k).is_err())
        .count();
    assert!(
        moved > first.len() / 20,
        "the robot's pixels move: {moved} of {} left",
        first.len()
    );
    // the tiles under it sink: reddish tile pixels appear
    let reddish = |f: &[u8]| {
        f.chunks_exact(3)
            .filter(|p| p[0] > 190 && p[1] < 150 && p[1].abs_diff(p[2]) < 8)
            .count()
    };
    assert!(reddish(&shown[45]) > 100, "sunk tiles are red");

    // eval: the first episode, at another rate
    let eval_gif = dir.join("eval.gif");
    let e = json_of(&[
        "eval",
        "--policy",
        "scripted",
        "--terrain",
        "rigid",
        "--episodes",
        "2",
        "--phases",
        "2",
        "--seed",
        "5",
        "--out",
        s(&dir.join("eval")),
        "--video",
        s(&eval_gif),
        "--video-fps",
        "10",
        "--video-size",
        "320x240",
        "--json",
    ]);
    // 240 / 10 = 24 steps a frame: 1 + 360 / 24 frames
    assert_eq!(e["video"]["frames"], 16, "{e}");
    assert_eq!(e["video"]["seed"], 5);
    assert_eq!(frames(&eval_gif).0.len(), 16);
}

#[test]
fn bad_video_paths_and_sizes_are_refused_before_the_run() {
    let dir = scratch_dir("video-bad");
    let missing = dir.join("no-such-dir").join("out.gif");
    let err = failure(&["rollout", "--phases", "1", "--video", s(&missing)], 1);
    assert!(
        err.contains("no-such-dir") && err.contains("does not exist"),
        "{err}"
    );
    let mp4 = dir.join("out.mp4");
    let err = failure(&["rollout", "--phases", "1", "--video", s(&mp4)], 1);
    assert!(err.contains("out.mp4") && err.contains(".gif"), "{err}");
    assert!(!mp4.exists());
    let gif = dir.join("out.gif");
    let err = failure(&["rollout", "--video", s(&gif), "--video-size", "10x10"], 2);
    assert!(
        err.contains("10x10") && err.contains("WIDTHxHEIGHT"),
        "{err}"
    );
    let err = failure(&["rollout", "--video-fps", "10"], 2);
    assert!(err.contains("--video"), "{err}");
    let err = failure(&["eval", "--compare", s(&dir), "--video", s(&gif)], 2);
    assert!(err.contains("--video"), "{err}");
    assert!(!gif.exists(), "nothing written");
}
