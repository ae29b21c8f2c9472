//! The five reward terms of a phase and their formulas (the paper's, and
//! the options described in the module docs of [`super`]).

use super::config::BalanceTerms;

/// The five reward terms of one phase.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct RewardTerms {
    /// goal distance (progress)
    pub distance: f64,
    /// goal orientation
    pub orientation: f64,
    /// minimum height
    pub height: f64,
    /// torque
    pub torque: f64,
    /// roll
    pub roll: f64,
}

impl RewardTerms {
    /// Term names, in the order of [`Self::values`].
    pub const NAMES: [&'static str; 5] = ["distance", "orientation", "height", "torque", "roll"];

    /// The terms as an array.
    pub fn values(&self) -> [f64; 5] {
        [
            self.distance,
            self.orientation,
            self.height,
            self.torque,
            self.roll,
        ]
    }

    /// These terms with the balance terms paid as `balance` says.
    pub fn with_balance(self, balance: BalanceTerms) -> Self {
        match balance {
            BalanceTerms::Paper => self,
            BalanceTerms::Penalty => {
                let [o, s, t, r] = Self::BALANCE_MAXIMA;
                Self {
                    orientation: self.orientation - o,
                    height: self.height - s,
                    torque: self.torque - t,
                    roll: self.roll - r,
                    ..self
                }
            }
        }
    }

    /// Their sum.
    pub fn total(&self) -> f64 {
        self.values().iter().sum()
    }

    /// R_d = alpha_d (|rho_prev| - |rho|), alpha_d = 10 when closer, else 1.
    pub fn distance_term(goal_distance_prev_m: f64, goal_distance_m: f64) -> f64 {
        let alpha = if goal_distance_prev_m > goal_distance_m {
            10.0
        } else {
            1.0
        };
        alpha * (goal_distance_prev_m - goal_distance_m)
    }

    /// [`DistanceReward::NewGround`]:
    /// w min((closest_before - now)+, cap) - (now - prev)+, with
    /// `closest_before_m` the closest approach to the goal earlier in the
    /// episode (at most `goal_distance_prev_m`), `max_paid_m` the cap on
    /// the new ground paid in one phase (`f64::INFINITY`: no cap) and
    /// `paid_per_m` the weight w (10 in the recipes: the paper's alpha_d
    /// for an approach). New ground past the cap is covered but unpaid: a
    /// faster pace earns nothing more.
    pub fn new_ground_term(
        closest_before_m: f64,
        goal_distance_prev_m: f64,
        goal_distance_m: f64,
        max_paid_m: f64,
        paid_per_m: f64,
    ) -> f64 {
        paid_per_m
            * (closest_before_m - goal_distance_m)
                .max(0.0)
                .min(max_paid_m)
            - (goal_distance_m - goal_distance_prev_m).max(0.0)
    }

    /// [`DistanceReward::Forward`]: weight (|rho_prev| - |rho|).
    pub fn forward_term(goal_distance_prev_m: f64, goal_distance_m: f64, weight_per_m: f64) -> f64 {
        weight_per_m * (goal_distance_prev_m - goal_distance_m)
    }

    /// [`DistanceReward::Tracking`](super::DistanceReward::Tracking):
    /// exp(-((p - p*) / (p* / 2))^2) for progress p and target p*.
    pub fn tracking_term(progress_m: f64, target_progress_m: f64) -> f64 {
        let sigma = 0.5 * target_progress_m;
        (-((progress_m - target_progress_m) / sigma).powi(2)).exp()
    }

    /// The best value of each balance term (R_o, R_s, R_t, R_r), what
    /// [`BalanceTerms::Penalty`] subtracts.
    pub const BALANCE_MAXIMA: [f64; 4] = [0.2, 0.1, 0.56, 0.2];

    /// R_o = max(0, 0.02 (10 - |phi_g| degrees)).
    pub fn orientation_term(goal_azimuth_rad: f64) -> f64 {
        (0.02 * (10.0 - goal_azimuth_rad.to_degrees().abs())).max(0.0)
    }

    /// R_s = 0.1 if the base height > 25 cm.
    pub fn height_term(base_height_m: f64) -> f64 {
        if base_height_m > 0.25 { 0.1 } else { 0.0 }
    }

    /// R_t = max(0, 0.004 (140 - tau_ave)).
    pub fn torque_term(mean_torque_norm_n_m: f64) -> f64 {
        (0.004 * (140.0 - mean_torque_norm_n_m)).max(0.0)
    }

    /// R_r = max(0, 2 (0.1 - |roll| rad)).
    pub fn roll_term(roll_rad: f64) -> f64 {
        (2.0 * (0.1 - roll_rad.abs())).max(0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reward_terms_follow_their_formulas() {
        // R_d: progress 0.1 m toward the goal pays 10 x 0.1; moving away 0.1 m costs 0.1.
        assert!((RewardTerms::distance_term(2.0, 1.9) - 1.0).abs() < 1e-12);
        assert!((RewardTerms::distance_term(1.9, 2.0) + 0.1).abs() < 1e-12);
        assert_eq!(RewardTerms::distance_term(2.0, 2.0), 0.0);
        // New ground: rocking 0.1 m forward, back, forward again earns the
        // paper's term 1.0 - 0.1 + 1.0 but here 1.0 - 0.1 + 0.0; going on
        // past the closest approach pays 10x again.
        let paper: f64 = [(2.0, 1.9), (1.9, 2.0), (2.0, 1.9)]
            .iter()
            .map(|&(a, b)| RewardTerms::distance_term(a, b))
            .sum();
        assert!((paper - 1.9).abs() < 1e-12);
        assert!(
            (RewardTerms::new_ground_term(2.0, 2.0, 1.9, f64::INFINITY, 10.0) - 1.0).abs() < 1e-12
        );
        assert!(
            (RewardTerms::new_ground_term(1.9, 1.9, 2.0, f64::INFINITY, 10.0) + 0.1).abs() < 1e-12
        );
        assert!(RewardTerms::new_ground_term(1.9, 2.0, 1.9, f64::INFINITY, 10.0).abs() < 1e-12);
        assert!(
            (RewardTerms::new_ground_term(1.9, 2.0, 1.8, f64::INFINITY, 10.0) - 1.0).abs() < 1e-12
        );
        // half of a forward step is new ground: 10 x 0.05 (no loss)
        assert!(
            (RewardTerms::new_ground_term(1.85, 1.9, 1.8, f64::INFINITY, 10.0) - 0.5).abs() < 1e-12
        );
        // a cap of 4 cm per phase: a 10 cm step pays 10 x 0.04, a 3 cm step
        // its full 10 x 0.03, and a step back costs what it did
        assert!((RewardTerms::new_ground_term(2.0, 2.0, 1.9, 0.04, 10.0) - 0.4).abs() < 1e-12);
        assert!((RewardTerms::new_ground_term(2.0, 2.0, 1.97, 0.04, 10.0) - 0.3).abs() < 1e-12);
        assert!((RewardTerms::new_ground_term(1.9, 1.9, 2.0, 0.04, 10.0) + 0.1).abs() < 1e-12);
        // a weight of 20 per metre doubles the new ground's pay, not what a
        // step back costs
        assert!((RewardTerms::new_ground_term(2.0, 2.0, 1.97, 0.04, 20.0) - 0.6).abs() < 1e-12);
        assert!((RewardTerms::new_ground_term(1.9, 1.9, 2.0, 0.04, 20.0) + 0.1).abs() < 1e-12);
        // R_o = max(0, 0.02 (10 - |phi| deg)).
        assert!((RewardTerms::orientation_term(0.0) - 0.2).abs() < 1e-12);
        assert!((RewardTerms::orientation_term(5f64.to_radians()) - 0.1).abs() < 1e-12);
        assert!((RewardTerms::orientation_term(-5f64.to_radians()) - 0.1).abs() < 1e-12);
        assert_eq!(RewardTerms::orientation_term(20f64.to_radians()), 0.0);
        // R_s = 0.1 above 25 cm.
        assert_eq!(RewardTerms::height_term(0.26), 0.1);
        assert_eq!(RewardTerms::height_term(0.24), 0.0);
        // R_t = max(0, 0.004 (140 - tau)).
        assert!((RewardTerms::torque_term(40.0) - 0.4).abs() < 1e-12);
        assert_eq!(RewardTerms::torque_term(200.0), 0.0);
        // R_r = max(0, 2 (0.1 - |roll|)).
        assert!((RewardTerms::roll_term(0.0) - 0.2).abs() < 1e-12);
        assert!((RewardTerms::roll_term(-0.05) - 0.1).abs() < 1e-12);
        assert_eq!(RewardTerms::roll_term(0.2), 0.0);
        let terms = RewardTerms {
            distance: 1.0,
            orientation: 0.2,
            height: 0.1,
            torque: 0.4,
            roll: 0.2,
        };
        assert!((terms.total() - 1.9).abs() < 1e-12);
    }

    #[test]
    fn forward_progress_and_balance_penalties() {
        // tracking: 1 at the target pace, e^-1 at p* +- p*/2,
        // e^-4 standing still, nothing for a 10 cm lunge
        assert!((RewardTerms::tracking_term(0.025, 0.025) - 1.0).abs() < 1e-12);
        assert!((RewardTerms::tracking_term(0.0375, 0.025) - (-1f64).exp()).abs() < 1e-12);
        assert!((RewardTerms::tracking_term(0.0, 0.025) - (-4f64).exp()).abs() < 1e-12);
        assert!(RewardTerms::tracking_term(0.10, 0.025) < 1e-15);
        // forward: the same weight both ways, so rocking nets nothing
        assert!((RewardTerms::forward_term(2.0, 1.98, 40.0) - 0.8).abs() < 1e-9);
        assert!((RewardTerms::forward_term(1.98, 2.0, 40.0) + 0.8).abs() < 1e-9);
        // each balance term's best value is its maximum over its input
        let best = RewardTerms {
            distance: 0.0,
            orientation: RewardTerms::orientation_term(0.0),
            height: RewardTerms::height_term(0.3),
            torque: RewardTerms::torque_term(0.0),
            roll: RewardTerms::roll_term(0.0),
        };
        assert_eq!(
            [best.orientation, best.height, best.torque, best.roll],
            RewardTerms::BALANCE_MAXIMA
        );
        // penalties: best is 0, the rest keeps its shape
        let shifted = best.with_balance(BalanceTerms::Penalty);
        assert!(shifted.total().abs() < 1e-12, "{shifted:?}");
        let standing = RewardTerms {
            distance: 0.0,
            orientation: 0.2,
            height: 0.1,
            torque: RewardTerms::torque_term(35.0),
            roll: 0.18,
        };
        let p = standing.with_balance(BalanceTerms::Penalty);
        assert!((p.torque - -0.14).abs() < 1e-9);
        assert!((p.roll - -0.02).abs() < 1e-9);
        assert!((standing.total() - p.total() - 1.06).abs() < 1e-9);
        assert_eq!(standing.with_balance(BalanceTerms::Paper), standing);
    }
}
