//! Aggregates over an evaluation's episodes: success, distance percentiles,
//! falls by cause and link, and the per-terrain-type split with the paper's
//! Table I quantities and Fig. 4 curve.

use std::collections::BTreeMap;

use robot::model::LegName;
use serde::{Deserialize, Serialize};

use super::record::{ANGLE_BINS, Accumulator, EpisodeRecord, TerrainSamples};
use super::response::ResponseSummary;

/// The label of the column that pools every terrain type (the paper's
/// T^ave).
pub const ALL_TERRAIN: &str = "all";

/// The `p`-th percentile (0-100) of `values` by linear interpolation between
/// the order statistics (NumPy's default): rank p/100 (n - 1). `None` when
/// empty.
pub fn percentile(values: &[f64], p: f64) -> Option<f64> {
    if values.is_empty() {
        return None;
    }
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    let rank = p.clamp(0.0, 100.0) / 100.0 * (sorted.len() - 1) as f64;
    let (lo, hi) = (rank.floor() as usize, rank.ceil() as usize);
    Some(sorted[lo] + (sorted[hi] - sorted[lo]) * (rank - lo as f64))
}

/// Mean, median, 10th and 90th percentile, extremes.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Spread {
    /// mean
    pub mean: f64,
    /// median
    pub median: f64,
    /// 10th percentile
    pub p10: f64,
    /// 90th percentile
    pub p90: f64,
    /// smallest
    pub min: f64,
    /// largest
    pub max: f64,
}

impl Spread {
    /// All zero (no values).
    pub fn zero() -> Self {
        Self::of(&[])
    }

    /// Of `values` (all zero when empty).
    pub fn of(values: &[f64]) -> Self {
        let at = |p| percentile(values, p).unwrap_or(0.0);
        Self {
            mean: if values.is_empty() {
                0.0
            } else {
                values.iter().sum::<f64>() / values.len() as f64
            },
            median: at(50.0),
            p10: at(10.0),
            p90: at(90.0),
            min: at(0.0),
            max: at(100.0),
        }
    }
}

/// Mean and spread of a quantity, with its sample count (`None` without
/// samples).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MeanStd {
    /// mean
    pub mean: Option<f64>,
    /// population standard deviation
    pub std: Option<f64>,
    /// samples
    pub count: u64,
}

impl From<&Accumulator> for MeanStd {
    fn from(a: &Accumulator) -> Self {
        Self {
            mean: a.mean(),
            std: a.std(),
            count: a.count,
        }
    }
}

/// One terrain type's figures (or all of them pooled).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TerrainSummary {
    /// the terrain type's label, or [`ALL_TERRAIN`]
    pub terrain: String,
    /// phases walked on it
    pub phases: usize,
    /// distance walked on it along x, m
    pub distance_m: f64,
    /// distance over the time of those phases, m/s
    pub mean_speed_m_per_s: f64,
    /// falls in its phases, by cause
    pub falls: BTreeMap<String, usize>,
    /// falls per 100 phases on it
    pub falls_per_100_phases: f64,
    /// h_b over every physics step (Table I's mu and sigma), m
    pub base_height_m: MeanStd,
    /// target landing height relative to the squat per swing foot
    /// (Table I's mu(fr) .. mu(rl)), keyed `FR`, `FL`, `RR`, `RL`, m
    pub landing_height_m: BTreeMap<String, MeanStd>,
    /// h_b by phase angle (Fig. 4): bin k covers [k, k + 1) degrees of the
    /// FL, RR, FR, RL cycle, m
    pub base_height_by_angle_m: Vec<MeanStd>,
}

impl TerrainSummary {
    /// From the merged samples of one terrain type; `phase_secs` is a
    /// phase's duration.
    pub fn from_samples(terrain: &str, s: &TerrainSamples, phase_secs: f64) -> Self {
        let falls_total: usize = s.falls.values().sum();
        Self {
            terrain: terrain.to_string(),
            phases: s.phases,
            distance_m: s.distance_m,
            mean_speed_m_per_s: if s.phases > 0 {
                s.distance_m / (s.phases as f64 * phase_secs)
            } else {
                0.0
            },
            falls: s.falls.clone(),
            falls_per_100_phases: if s.phases > 0 {
                100.0 * falls_total as f64 / s.phases as f64
            } else {
                0.0
            },
            base_height_m: (&s.base_height_m).into(),
            landing_height_m: LegName::ALL
                .iter()
                .map(|leg| {
                    (
                        leg.short().to_string(),
                        (&s.landing_height_m[leg.index()]).into(),
                    )
                })
                .collect(),
            base_height_by_angle_m: s.base_height_by_angle_m.iter().map(Into::into).collect(),
        }
    }
}

/// The bins of [`Summary::falls_after_a_goal_by_goal_ahead`]: the current
/// goal's distance ahead of the base at the fall, m.
pub const GOAL_AHEAD_BINS: [&str; 4] = ["< 0.5 m", "0.5-1 m", "1-1.5 m", ">= 1.5 m"];

/// The [`GOAL_AHEAD_BINS`] index of a goal `ahead_m` ahead.
pub fn goal_ahead_bin(ahead_m: f64) -> usize {
    ((ahead_m / 0.5).floor().max(0.0) as usize).min(GOAL_AHEAD_BINS.len() - 1)
}

/// What every episode together shows.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    /// episodes run
    pub episodes: usize,
    /// episodes that ran all their phases without falling
    pub successes: usize,
    /// successes / episodes
    pub success_rate: f64,
    /// distance along x per episode, m
    pub distance_m: Spread,
    /// mean speed per episode, m/s
    pub mean_speed_m_per_s: Spread,
    /// phases survived per episode
    pub phases: Spread,
    /// goals reached per episode
    pub goals_reached: Spread,
    /// mean joint torque norm per episode, N m
    pub mean_torque_n_m: Spread,
    /// cost of transport, every episode pooled: the joints' mechanical
    /// energy summed over the episodes over m g times their summed distance
    /// (`None` unless they walked forward together); absent in files written
    /// before 2026-12-02
    #[serde(default)]
    pub cost_of_transport: Option<f64>,
    /// foot slip per phase, per episode (horizontal foot travel while
    /// touching the ground over the phases run), m
    #[serde(default = "Spread::zero")]
    pub foot_slip_m_per_phase: Spread,
    /// falls by cause
    pub falls_by_cause: BTreeMap<String, usize>,
    /// non-foot contacts that ended an episode, by link
    pub falls_by_link: BTreeMap<String, usize>,
    /// falls at the terrain's far end (walked off a field too short for
    /// the episode), counted in the causes above too
    #[serde(default)]
    pub falls_at_terrain_end: usize,
    /// falls after at least one goal was reached, by the current goal's
    /// distance ahead ([`GOAL_AHEAD_BINS`]): a goal reached puts the next
    /// one 2 m ahead, so falls bunched in the last bin come within half a
    /// metre of a goal switch
    #[serde(default)]
    pub falls_after_a_goal_by_goal_ahead: [usize; 4],
    /// every terrain type pooled ([`ALL_TERRAIN`]), then each type by label
    pub terrain_types: Vec<TerrainSummary>,
    /// on a terrain that changes by itself (`switch`): the responses to the
    /// change (see [`super::response`])
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub change_response: Option<ResponseSummary>,
}

impl Summary {
    /// Aggregates `episodes` (any order); `phase_secs` is a phase's duration.
    pub fn of(episodes: &[EpisodeRecord], phase_secs: f64) -> Self {
        let column = |f: &dyn Fn(&EpisodeRecord) -> f64| {
            Spread::of(&episodes.iter().map(f).collect::<Vec<_>>())
        };
        let successes = episodes.iter().filter(|e| e.succeeded()).count();
        let mut falls_by_cause = BTreeMap::new();
        let mut falls_by_link = BTreeMap::new();
        let mut falls_at_terrain_end = 0;
        let mut falls_after_a_goal_by_goal_ahead = [0; 4];
        for episode in episodes {
            let Some(fall) = &episode.fall else {
                continue;
            };
            if let Some(ahead_m) = fall.goal_ahead_m.filter(|_| episode.goals_reached > 0) {
                falls_after_a_goal_by_goal_ahead[goal_ahead_bin(ahead_m)] += 1;
            }
            falls_at_terrain_end += usize::from(fall.at_terrain_end);
            *falls_by_cause.entry(fall.cause.clone()).or_default() += 1;
            for link in &fall.links {
                *falls_by_link.entry(link.clone()).or_default() += 1;
            }
        }
        let mut merged: BTreeMap<String, TerrainSamples> = BTreeMap::new();
        let mut all = TerrainSamples::default();
        for episode in episodes {
            for (label, samples) in &episode.by_terrain {
                merged.entry(label.clone()).or_default().merge(samples);
                all.merge(samples);
            }
        }
        let mut terrain_types = vec![TerrainSummary::from_samples(ALL_TERRAIN, &all, phase_secs)];
        terrain_types.extend(
            merged
                .iter()
                .map(|(label, s)| TerrainSummary::from_samples(label, s, phase_secs)),
        );
        Self {
            episodes: episodes.len(),
            successes,
            success_rate: if episodes.is_empty() {
                0.0
            } else {
                successes as f64 / episodes.len() as f64
            },
            distance_m: column(&|e| e.distance_m),
            mean_speed_m_per_s: column(&|e| e.mean_speed_m_per_s),
            phases: column(&|e| e.phases as f64),
            goals_reached: column(&|e| e.goals_reached as f64),
            mean_torque_n_m: column(&|e| e.mean_torque_n_m),
            cost_of_transport: pooled_cost_of_transport(episodes),
            foot_slip_m_per_phase: column(&|e| e.foot_slip_m / e.phases.max(1) as f64),
            falls_by_cause,
            falls_by_link,
            falls_at_terrain_end,
            falls_after_a_goal_by_goal_ahead,
            terrain_types,
            change_response: ResponseSummary::of(
                episodes.iter().find_map(|e| e.terrain_change_secs),
                &episodes
                    .iter()
                    .map(|e| e.change_response.clone())
                    .collect::<Vec<_>>(),
            ),
        }
    }

    /// The falls by cause as text (`base_too_low 2, non_foot_contact 1`,
    /// or `none`).
    pub fn falls_text(&self) -> String {
        if self.falls_by_cause.is_empty() {
            return "none".to_string();
        }
        self.falls_by_cause
            .iter()
            .map(|(c, n)| format!("{c} {n}"))
            .collect::<Vec<_>>()
            .join(", ")
    }

    /// The terrain types with samples, each by itself (without the pooled
    /// column).
    pub fn each_terrain_type(&self) -> impl Iterator<Item = &TerrainSummary> {
        self.terrain_types
            .iter()
            .filter(|t| t.terrain != ALL_TERRAIN)
    }
}

/// The cost of transport of `episodes` together: their mechanical energy
/// over m g times their distance; `None` unless they walked forward
/// together.
fn pooled_cost_of_transport(episodes: &[EpisodeRecord]) -> Option<f64> {
    let energy_j: f64 = episodes.iter().map(|e| e.mechanical_energy_j).sum();
    let distance_m: f64 = episodes.iter().map(|e| e.distance_m).sum();
    let weight_n = episodes.first()?.robot_weight_n;
    (distance_m > 0.0 && weight_n > 0.0).then(|| energy_j / (weight_n * distance_m))
}

/// Bins per degree of the phase angle (for plots and axes).
pub fn angle_bin_centre_deg(bin: usize) -> f64 {
    (bin as f64 + 0.5) * 360.0 / ANGLE_BINS as f64
}

#[cfg(test)]
pub(crate) mod tests {
    use super::super::record::{Fall, PhaseRecord};
    use super::*;

    #[test]
    fn percentiles_interpolate_between_order_statistics() {
        let v = [5.0, 1.0, 4.0, 2.0, 3.0];
        assert_eq!(percentile(&v, 0.0), Some(1.0));
        assert_eq!(percentile(&v, 50.0), Some(3.0));
        assert_eq!(percentile(&v, 100.0), Some(5.0));
        // rank 0.1 * 4 = 0.4: 1 + 0.4 (2 - 1)
        assert!((percentile(&v, 10.0).unwrap() - 1.4).abs() < 1e-12);
        // rank 3.6: 4 + 0.6 (5 - 4)
        assert!((percentile(&v, 90.0).unwrap() - 4.6).abs() < 1e-12);
        assert_eq!(percentile(&[], 50.0), None);
        assert_eq!(percentile(&[7.0], 90.0), Some(7.0));
    }

    /// An episode on `terrains` (one phase each, 1 m per phase) that falls
    /// with `fall` in its last phase, if given.
    /// An episode of `seed` with one phase (1 m) per terrain named, and the
    /// fall given (its cause and links).
    pub(crate) fn crafted(
        seed: u64,
        terrains: &[&str],
        fall: Option<(&str, &[&str])>,
    ) -> EpisodeRecord {
        let mut by_terrain: BTreeMap<String, TerrainSamples> = BTreeMap::new();
        for t in terrains {
            let s = by_terrain.entry(t.to_string()).or_default();
            s.phases += 1;
            s.distance_m += 1.0;
        }
        let fall = fall.map(|(cause, links)| {
            let last = terrains.last().unwrap().to_string();
            *by_terrain
                .get_mut(&last)
                .unwrap()
                .falls
                .entry(cause.into())
                .or_default() += 1;
            Fall {
                cause: cause.into(),
                detail: cause.into(),
                links: links.iter().map(|l| l.to_string()).collect(),
                phase: terrains.len() - 1,
                terrain: last,
                at_terrain_end: false,
                goal_ahead_m: Some(1.8),
            }
        });
        EpisodeRecord {
            seed,
            start_xy_m: [0.0, 0.0],
            phases: terrains.len(),
            distance_m: terrains.len() as f64,
            lateral_drift_m: 0.0,
            mean_speed_m_per_s: 1.0 / 0.75,
            goals_reached: 0,
            fall,
            mean_torque_n_m: 10.0,
            mechanical_energy_j: 0.0,
            cost_of_transport: None,
            foot_slip_m: 0.0,
            robot_weight_n: 0.0,
            reward_total: 0.0,
            terrain_change_secs: None,
            change_response: None,
            phase_log: terrains
                .iter()
                .map(|t| PhaseRecord {
                    swing: "FL".into(),
                    terrain: t.to_string(),
                    mean_base_height_m: 0.3,
                    landing_height_m: 0.0,
                    distance_m: 1.0,
                })
                .collect(),
            by_terrain,
        }
    }

    #[test]
    fn success_distance_falls_and_the_terrain_split_add_up() {
        let episodes = vec![
            crafted(0, &["rigid", "rigid", "elastic:5cm", "elastic:5cm"], None),
            crafted(
                1,
                &["rigid", "elastic:5cm"],
                Some(("non_foot_contact", &["FR_lower_leg", "base"])),
            ),
            crafted(2, &["elastic:5cm"], Some(("base_too_low", &[]))),
            crafted(3, &["rigid", "rigid", "rigid"], None),
        ];
        let mut episodes = episodes;
        // episode 2 fell where the field ends: a fall, and counted as such
        let end = episodes[2].fall.as_mut().unwrap();
        end.at_terrain_end = true;
        assert_eq!(end.describe(), "base_too_low at the end of the terrain");
        assert_eq!(
            episodes[1].fall.as_ref().unwrap().describe(),
            "non_foot_contact"
        );
        let s = Summary::of(&episodes, 0.75);
        assert_eq!(
            s.falls_after_a_goal_by_goal_ahead, [0; 4],
            "no episode reached a goal"
        );
        // after a goal: episode 1 fell 1.8 m short of the next (just past
        // the switch), episode 2 0.3 m short of it; a goal 2 m behind
        // counts in the first bin
        episodes[1].goals_reached = 3;
        episodes[2].goals_reached = 1;
        episodes[2].fall.as_mut().unwrap().goal_ahead_m = Some(0.3);
        let s = Summary::of(&episodes, 0.75);
        assert_eq!(s.falls_after_a_goal_by_goal_ahead, [1, 0, 0, 1]);
        assert_eq!(goal_ahead_bin(-2.0), 0);
        assert_eq!(goal_ahead_bin(0.5), 1);
        assert_eq!(goal_ahead_bin(1.49), 2);
        assert_eq!(goal_ahead_bin(2.3), 3);
        assert_eq!(s.falls_at_terrain_end, 1);
        assert_eq!(s.episodes, 4);
        assert_eq!(s.successes, 2);
        assert_eq!(s.success_rate, 0.5);
        // distances 4, 2, 1, 3
        assert_eq!(s.distance_m.mean, 2.5);
        assert_eq!(s.distance_m.median, 2.5);
        assert!((s.distance_m.p10 - 1.3).abs() < 1e-12);
        assert!((s.distance_m.p90 - 3.7).abs() < 1e-12);
        assert_eq!(s.falls_by_cause["non_foot_contact"], 1);
        assert_eq!(s.falls_by_cause["base_too_low"], 1);
        assert_eq!(s.falls_by_link["FR_lower_leg"], 1);
        assert_eq!(s.falls_by_link["base"], 1);
        let labels: Vec<_> = s.terrain_types.iter().map(|t| t.terrain.as_str()).collect();
        assert_eq!(labels, [ALL_TERRAIN, "elastic:5cm", "rigid"]);
        let soft = &s.terrain_types[1];
        assert_eq!(soft.phases, 4);
        assert_eq!(soft.distance_m, 4.0);
        assert_eq!(soft.falls.values().sum::<usize>(), 2);
        assert_eq!(soft.falls_per_100_phases, 50.0);
        let rigid = &s.terrain_types[2];
        assert_eq!(rigid.phases, 6);
        assert!(rigid.falls.is_empty());
        assert!((rigid.mean_speed_m_per_s - 1.0 / 0.75).abs() < 1e-12);
        let all = &s.terrain_types[0];
        assert_eq!(all.phases, 10);
        assert_eq!(all.distance_m, 10.0);
        assert_eq!(s.each_terrain_type().count(), 2);
    }
}
