//! The networks' activation, tanh, in two implementations that a learner's
//! settings choose between (`[ppo] tanh`):
//!
//! - `"libm"` (the default): candle's `tanh`, which calls the platform's C
//!   library (`tanhf`) once per value. With glibc 2.36 that is ~12 ns a
//!   value, and PPO's update with mirrored minibatches of 256 rows through
//!   two 256-128 networks evaluates ~20 million of them an iteration: about
//!   40 % of the update's time (`perf record` of `quadwalk train`,
//!   docs/notebook/2026-12-06-issue40-tanh-endings.md).
//! - `"polynomial"`: quadwalk's own, straight-line arithmetic that inlines
//!   into the loop over the values (no call per value, ~4.5 ns a value),
//!   computed in `f64` and rounded to `f32`:
//!
//!   ```text
//!   tanh x = sign(x) t,   t = m / (m + 2),   m = e^{2|x|} - 1
//!   e^y - 1 = 2^k (e^r - 1) + (2^k - 1),   y = k ln 2 + r,  |r| <= ln 2 / 2
//!   e^r - 1 = r (1 + r/2 (1 + r/3 (... (1 + r/11))))   (Taylor, error < 1e-12)
//!   ```
//!
//!   with `|x|` capped at 10 (tanh 10 rounds to 1 in `f32`). For `k = 0`
//!   the form `m / (m + 2)` has no cancellation, so small `x` keep their
//!   relative accuracy. The result is the `f64` tanh rounded to `f32` (0
//!   ulp apart on a sweep of every 97th `f32`, in the tests below a sweep of
//!   every 4099th), so within 1 ulp of the true tanh, as libm's is, and the
//!   same bits on every platform. glibc's `tanhf` is documented within 2
//!   ulps and differs from it in the last bits for ~3 % of inputs, so a
//!   run's numbers differ from the same run with `"libm"`: a new run, not a
//!   faster copy of an old one.
//!
//! The gradient is `d tanh x / dx = 1 - tanh^2 x`, from the forward's output.

use candle_core::{CpuStorage, CustomOp1, Layout, Shape, Tensor};
use serde::{Deserialize, Serialize};

/// Which tanh a network evaluates between its layers.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum TanhImpl {
    /// candle's, the platform's C library `tanhf` per value
    #[default]
    Libm,
    /// quadwalk's `f64` range reduction and polynomial, rounded to `f32`
    Polynomial,
}

impl TanhImpl {
    /// Whether this is the default (`"libm"`): settings files leave it out.
    pub fn is_libm(&self) -> bool {
        *self == Self::Libm
    }

    /// `tanh` of every value of `x`, with its gradient recorded.
    pub fn apply(self, x: &Tensor) -> candle_core::Result<Tensor> {
        match self {
            Self::Libm => x.tanh(),
            Self::Polynomial => x.contiguous()?.apply_op1(PolynomialTanh),
        }
    }
}

/// ln 2 split so that `k * LN2_HI` is exact for the `k` used (<= 29).
const LN2_HI: f64 = 0.693_147_180_369_123_8;
const LN2_LO: f64 = 1.908_214_929_270_587_7e-10;
/// 1.5 * 2^52: adding it rounds a value below 2^51 to an integer, which
/// the sum's low mantissa bits then hold.
const ROUNDING_SHIFTER: f64 = 6_755_399_441_055_744.0;
/// `|x|` at and above which `tanh x` rounds to 1 in `f32` (tanh 10 = 1 - 4e-9)
const SATURATION: f64 = 10.0;

/// tanh of one value by the polynomial (see the module's text).
#[inline(always)]
pub fn polynomial_tanh(x: f32) -> f32 {
    let a = f64::from(x).abs().min(SATURATION);
    let y = a + a;
    let shifted = y * std::f64::consts::LOG2_E + ROUNDING_SHIFTER;
    let k_float = shifted - ROUNDING_SHIFTER;
    let k = shifted.to_bits().wrapping_sub(ROUNDING_SHIFTER.to_bits());
    let r = (y - k_float * LN2_HI) - k_float * LN2_LO;
    let mut q = 1.0 / 39_916_800.0;
    for inverse_factorial in [
        1.0 / 3_628_800.0,
        1.0 / 362_880.0,
        1.0 / 40_320.0,
        1.0 / 5_040.0,
        1.0 / 720.0,
        1.0 / 120.0,
        1.0 / 24.0,
        1.0 / 6.0,
        0.5,
        1.0,
    ] {
        q = q * r + inverse_factorial;
    }
    let expm1_r = q * r;
    let two_k = f64::from_bits((k + 1023) << 52);
    let m = two_k * expm1_r + (two_k - 1.0);
    let t = (m / (m + 2.0)) as f32;
    if x.is_nan() { x } else { t.copysign(x) }
}

/// The polynomial tanh as a candle op with a gradient.
struct PolynomialTanh;

impl CustomOp1 for PolynomialTanh {
    fn name(&self) -> &'static str {
        "polynomial-tanh"
    }

    fn cpu_fwd(
        &self,
        storage: &CpuStorage,
        layout: &Layout,
    ) -> candle_core::Result<(CpuStorage, Shape)> {
        let CpuStorage::F32(values) = storage else {
            return Err(candle_core::Error::Msg(
                "polynomial tanh takes f32 values".into(),
            ));
        };
        let Some((start, end)) = layout.contiguous_offsets() else {
            return Err(candle_core::Error::Msg(
                "polynomial tanh takes a contiguous tensor".into(),
            ));
        };
        let out: Vec<f32> = values[start..end]
            .iter()
            .map(|&x| polynomial_tanh(x))
            .collect();
        Ok((CpuStorage::F32(out), layout.shape().clone()))
    }

    fn bwd(
        &self,
        _arg: &Tensor,
        res: &Tensor,
        grad_res: &Tensor,
    ) -> candle_core::Result<Option<Tensor>> {
        // d tanh x / dx = 1 - tanh^2 x
        let derivative = res.sqr()?.affine(-1.0, 1.0)?;
        Ok(Some(grad_res.mul(&derivative)?))
    }
}

#[cfg(test)]
mod tests {
    use candle_core::{Device, Var};

    use super::*;

    /// Units in the last place between two finite `f32` of the same sign.
    fn ulps(a: f32, b: f32) -> u32 {
        a.to_bits().abs_diff(b.to_bits())
    }

    #[test]
    fn polynomial_tanh_is_the_f64_tanh_rounded() {
        let mut worst = 0;
        let mut bits = 0u32;
        loop {
            let x = f32::from_bits(bits);
            if x.is_finite() {
                let exact = f64::from(x).tanh() as f32;
                let got = polynomial_tanh(x);
                assert!(
                    ulps(got, exact) <= 1,
                    "tanh({x:e}) = {got:e}, f64 rounded {exact:e}"
                );
                worst = worst.max(ulps(got, exact));
            }
            let (next, wrapped) = bits.overflowing_add(4099);
            if wrapped {
                break;
            }
            bits = next;
        }
        assert_eq!(worst, 0, "at most 1 ulp, and on this sweep none");
    }

    #[test]
    fn polynomial_tanh_keeps_sign_zero_saturation_and_nan() {
        assert_eq!(polynomial_tanh(0.0).to_bits(), 0.0f32.to_bits());
        assert_eq!(polynomial_tanh(-0.0).to_bits(), (-0.0f32).to_bits());
        assert_eq!(polynomial_tanh(1e-30), 1e-30);
        assert_eq!(polynomial_tanh(-3e-8), -3e-8);
        assert_eq!(polynomial_tanh(9.5), 1.0);
        assert_eq!(polynomial_tanh(f32::INFINITY), 1.0);
        assert_eq!(polynomial_tanh(f32::NEG_INFINITY), -1.0);
        assert_eq!(polynomial_tanh(-1e30), -1.0);
        assert!(polynomial_tanh(f32::NAN).is_nan());
        for x in [0.1f32, 0.5, 1.0, 2.0, 4.0] {
            assert_eq!(polynomial_tanh(-x), -polynomial_tanh(x), "odd at {x}");
        }
    }

    #[test]
    fn both_implementations_agree_within_libms_error_with_the_same_gradient() {
        let xs: Vec<f32> = (0..2001).map(|i| (i as f32 - 1000.0) / 150.0).collect();
        let x = Var::from_vec(xs.clone(), (23, 87), &Device::Cpu).unwrap();
        let weights = Tensor::from_vec(
            (0..xs.len())
                .map(|i| ((i % 7) as f32 - 3.0) / 3.0)
                .collect::<Vec<_>>(),
            (23, 87),
            &Device::Cpu,
        )
        .unwrap();
        let mut results = Vec::new();
        for tanh in [TanhImpl::Libm, TanhImpl::Polynomial] {
            let y = tanh.apply(x.as_tensor()).unwrap();
            let loss = y.mul(&weights).unwrap().sum_all().unwrap();
            let grad = loss.backward().unwrap().get(x.as_tensor()).unwrap().clone();
            let flat = |t: &Tensor| t.flatten_all().unwrap().to_vec1::<f32>().unwrap();
            results.push((flat(&y), flat(&grad)));
        }
        let ((y_libm, g_libm), (y_poly, g_poly)) = (&results[0], &results[1]);
        for k in 0..xs.len() {
            // glibc documents tanhf within 2 ulps; the polynomial is within 1
            assert!(
                ulps(y_libm[k], y_poly[k]) <= 3,
                "tanh({}): {} {}",
                xs[k],
                y_libm[k],
                y_poly[k]
            );
            // d/dx = w (1 - y^2): a few ulps of y move it by ~1e-7 a ulp
            assert!(
                (g_libm[k] - g_poly[k]).abs() <= 4e-7,
                "gradient at {}",
                xs[k]
            );
        }
    }

    #[test]
    fn settings_spell_both_names_and_refuse_others() {
        #[derive(Deserialize)]
        struct Table {
            tanh: TanhImpl,
        }
        let parse = |text: &str| toml::from_str::<Table>(text).map(|t| t.tanh);
        assert_eq!(parse("tanh = \"libm\"").unwrap(), TanhImpl::Libm);
        assert_eq!(
            parse("tanh = \"polynomial\"").unwrap(),
            TanhImpl::Polynomial
        );
        let err = parse("tanh = \"fast\"").unwrap_err().to_string();
        assert!(err.contains("libm") && err.contains("polynomial"), "{err}");
    }
}
