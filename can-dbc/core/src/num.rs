//! The two float roundings the codec needs, without `std` (`f64::round` and `f64::trunc` are
//! std-only: they call libm). Both are exact and equal std's for every `f64`.

/// 2^52: from here on every `f64` is a whole number.
const WHOLE_FROM: f64 = 4_503_599_627_370_496.0;

/// `x` rounded towards zero, as [`f64::trunc`] (the sign of a zero result may differ).
pub(crate) fn trunc(x: f64) -> f64 {
    if x.abs() < WHOLE_FROM {
        // |x| < 2^52 fits an i64, and its whole part is exact in f64.
        x as i64 as f64
    } else {
        // Whole already, or not finite.
        x
    }
}

/// `x` rounded to the nearest whole number, halves away from zero, as [`f64::round`] (the sign
/// of a zero result may differ).
pub(crate) fn round(x: f64) -> f64 {
    let t = trunc(x);
    // Exact: the fractional part of an f64 is representable.
    let frac = x - t;
    if frac >= 0.5 {
        t + 1.0
    } else if frac <= -0.5 {
        t - 1.0
    } else {
        t
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn edges_agree_with_std() {
        let edges = [
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.5,
            -1.5,
            2.5,
            -2.5,
            0.49999999999999994,
            -0.49999999999999994,
            4503599627370495.5,
            -4503599627370495.5,
            WHOLE_FROM,
            1e300,
            -1e300,
            f64::MAX,
            f64::MIN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            2047.4999,
            -2048.5,
            1e-320,
        ];
        for x in edges {
            assert!(
                round(x) == x.round(),
                "round({x:e}) = {} vs std {}",
                round(x),
                x.round()
            );
            assert!(
                trunc(x) == x.trunc(),
                "trunc({x:e}) = {} vs std {}",
                trunc(x),
                x.trunc()
            );
        }
        assert!(round(f64::NAN).is_nan() && trunc(f64::NAN).is_nan());
    }

    proptest! {
        #[test]
        fn agrees_with_std(x in any::<f64>().prop_filter("finite", |x| x.is_finite())) {
            prop_assert!(round(x) == x.round());
            prop_assert!(trunc(x) == x.trunc());
        }

        #[test]
        fn agrees_with_std_on_the_codec_range(x in -1e7f64..1e7) {
            prop_assert!(round(x) == x.round());
            prop_assert!(trunc(x) == x.trunc());
        }
    }
}
