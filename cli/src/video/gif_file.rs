//! Frames streamed into a GIF file with one fixed palette: a 6 x 6 x 6
//! colour cube, 16 greys and 24 steps of the tiles' sink colours (grey to
//! red, `viz::sink_colour`). Every pixel maps to its nearest entry among
//! three candidates (the cube's, the greys' and the ramp's), so encoding is
//! fast and the same frames give the same file.

use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

/// Entries of the colour cube per channel.
const CUBE: u32 = 6;
/// Greys after the cube.
const GREYS: u32 = 16;
/// Steps of the sink colour ramp after the greys.
const RAMP: u32 = 24;

/// The sink colour of ramp step `k`.
fn ramp_colour(k: u32) -> [u8; 3] {
    viz::sink_colour(viz::FULL_COLOUR_SINK_M * f64::from(k) / f64::from(RAMP - 1))
}

/// The palette, RGB triples: the cube (index r 36 + g 6 + b), the greys,
/// the ramp.
fn palette() -> Vec<u8> {
    let mut p = Vec::with_capacity(3 * 256);
    for r in 0..CUBE {
        for g in 0..CUBE {
            for b in 0..CUBE {
                p.extend([r, g, b].map(|c| (c * 255 / (CUBE - 1)) as u8));
            }
        }
    }
    for k in 0..GREYS {
        let v = ((k + 1) * 255 / (GREYS + 1)) as u8;
        p.extend([v, v, v]);
    }
    for k in 0..RAMP {
        p.extend(ramp_colour(k));
    }
    debug_assert_eq!(p.len(), 3 * 256);
    p
}

fn distance2(a: [u8; 3], b: [u8; 3]) -> u32 {
    a.iter()
        .zip(b)
        .map(|(&x, y)| u32::from(x.abs_diff(y)).pow(2))
        .sum()
}

/// The palette index nearest to a pixel, of three candidates: the nearest
/// cube colour, the nearest grey and the nearest ramp step.
fn index_of(rgb: [u8; 3]) -> u8 {
    let [r, g, b] = rgb.map(u32::from);
    let level = |c: u32| (c * (CUBE - 1) + 127) / 255;
    let cube = level(r) * CUBE * CUBE + level(g) * CUBE + level(b);
    let cube_rgb = [level(r), level(g), level(b)].map(|c| (c * 255 / (CUBE - 1)) as u8);
    let mean = (r + g + b) / 3;
    let k = ((mean * (GREYS + 1) + 127) / 255).clamp(1, GREYS);
    let grey_value = (k * 255 / (GREYS + 1)) as u8;
    // the ramp runs from (170, 170, 170) to (230, 40, 40): project on it
    let (dr, dg) = (60.0, -130.0);
    let u = ((f64::from(r) - 170.0) * dr + (f64::from(g + b) / 2.0 - 170.0) * dg * 2.0)
        / (dr * dr + 2.0 * dg * dg);
    let step = (u.clamp(0.0, 1.0) * f64::from(RAMP - 1)).round() as u32;
    let candidates = [
        (cube, cube_rgb),
        (CUBE.pow(3) + k - 1, [grey_value; 3]),
        (CUBE.pow(3) + GREYS + step, ramp_colour(step)),
    ];
    candidates
        .into_iter()
        .min_by_key(|(_, c)| distance2(rgb, *c))
        .map_or(0, |(i, _)| i as u8)
}

/// A GIF being written, one frame at a time.
pub struct GifWriter {
    encoder: gif::Encoder<BufWriter<File>>,
    path: PathBuf,
    size_px: (u16, u16),
    delay_cs: u16,
    frames: usize,
}

impl GifWriter {
    /// Creates `path` for frames of `size_px`, looping, each frame shown
    /// `delay_cs` hundredths of a second until [`Self::set_delay_cs`].
    pub fn create(path: &Path, size_px: (u16, u16), delay_cs: u16) -> Result<Self> {
        let file = File::create(path)
            .with_context(|| format!("--video {}: cannot create the file", path.display()))?;
        let mut encoder = gif::Encoder::new(BufWriter::new(file), size_px.0, size_px.1, &palette())
            .with_context(|| format!("--video {}", path.display()))?;
        encoder
            .set_repeat(gif::Repeat::Infinite)
            .with_context(|| format!("--video {}", path.display()))?;
        Ok(Self {
            encoder,
            path: path.to_path_buf(),
            size_px,
            delay_cs,
            frames: 0,
        })
    }

    /// Appends a frame of RGB pixels (row by row, `size_px` of the file).
    pub fn push_rgb(&mut self, rgb: &[u8]) -> Result<()> {
        let (w, h) = self.size_px;
        debug_assert_eq!(rgb.len(), 3 * usize::from(w) * usize::from(h));
        let indices: Vec<u8> = rgb
            .chunks_exact(3)
            .map(|p| index_of([p[0], p[1], p[2]]))
            .collect();
        let mut frame = gif::Frame::from_indexed_pixels(w, h, indices, None);
        frame.delay = self.delay_cs;
        self.encoder
            .write_frame(&frame)
            .with_context(|| format!("--video {}: cannot write a frame", self.path.display()))?;
        self.frames += 1;
        Ok(())
    }

    /// How long the next frames are shown, hundredths of a second.
    pub fn set_delay_cs(&mut self, delay_cs: u16) {
        self.delay_cs = delay_cs;
    }

    /// The file being written.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Frames written so far.
    pub fn frames(&self) -> usize {
        self.frames
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_palette_holds_256_colours_and_pixels_map_to_their_nearest() {
        let p = palette();
        assert_eq!(p.len(), 3 * 256);
        let colour = |i: u8| {
            [
                p[3 * i as usize],
                p[3 * i as usize + 1],
                p[3 * i as usize + 2],
            ]
        };
        for rgb in [[255, 255, 255], [0, 0, 0], [255, 0, 0], [0, 102, 204]] {
            assert_eq!(colour(index_of(rgb)), rgb, "a cube colour maps to itself");
        }
        // a mid grey finds a grey within half a step of 255 / 17
        let grey = colour(index_of([120, 120, 120]));
        assert!(grey[0] == grey[1] && grey[1] == grey[2]);
        assert!(grey[0].abs_diff(120) <= 8, "{grey:?}");
        // every sink colour is in the palette exactly at its ramp steps,
        // and within a step between them
        for k in 0..RAMP {
            assert_eq!(colour(index_of(ramp_colour(k))), ramp_colour(k), "step {k}");
        }
        let half = viz::sink_colour(viz::FULL_COLOUR_SINK_M * 0.51);
        assert!(
            distance2(colour(index_of(half)), half) <= 3 * 4 * 4,
            "{half:?}"
        );
    }
}
