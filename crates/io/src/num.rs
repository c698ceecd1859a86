//! Validated numbers for command-line options and run parameters: one parser per kind of number,
//! so that no option accepts NaN, an infinity or a value outside its domain, and every refusal
//! states the allowed range with its unit.
//!
//! [`Real`] and [`Count`] are clap value parsers (`#[arg(long, value_parser = Real::positive("m"))]`):
//! a bad value is a usage error (exit 2) such as
//! `invalid value 'NaN' for '--near-radius <M>': must be a finite number >= 0 m`.
//! Their [`Real::check`] / [`Count::check`] validate numbers that arrive by other routes (a case
//! parameter `rho=0.5`, a field of a results file) with the same wording.

use std::ffi::OsStr;
use std::fmt;
use std::marker::PhantomData;

/// A bound of an interval: open (`<`) or closed (`<=`).
#[derive(Clone, Copy, Debug, PartialEq)]
enum Bound {
    Open(f64),
    Closed(f64),
    None,
}

/// A finite real number in an interval, with a unit for messages (`""` for dimensionless).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Real {
    lo: Bound,
    hi: Bound,
    unit: &'static str,
}

impl Real {
    /// Any finite number.
    pub const fn finite(unit: &'static str) -> Real {
        Real {
            lo: Bound::None,
            hi: Bound::None,
            unit,
        }
    }
    /// A finite number >= 0.
    pub const fn non_negative(unit: &'static str) -> Real {
        Real {
            lo: Bound::Closed(0.0),
            hi: Bound::None,
            unit,
        }
    }
    /// A finite number > 0.
    pub const fn positive(unit: &'static str) -> Real {
        Real {
            lo: Bound::Open(0.0),
            hi: Bound::None,
            unit,
        }
    }
    /// A number in the closed interval [lo, hi].
    pub const fn closed(lo: f64, hi: f64, unit: &'static str) -> Real {
        Real {
            lo: Bound::Closed(lo),
            hi: Bound::Closed(hi),
            unit,
        }
    }
    /// A number in [lo, hi): a reflectance of a closed room must stay below 1.
    pub const fn closed_open(lo: f64, hi: f64, unit: &'static str) -> Real {
        Real {
            lo: Bound::Closed(lo),
            hi: Bound::Open(hi),
            unit,
        }
    }
    /// A number in (lo, hi].
    pub const fn open_closed(lo: f64, hi: f64, unit: &'static str) -> Real {
        Real {
            lo: Bound::Open(lo),
            hi: Bound::Closed(hi),
            unit,
        }
    }
    /// The same interval with an upper bound `hi` (inclusive): a finite positive time, a bounded
    /// size.
    pub const fn at_most(self, hi: f64) -> Real {
        Real {
            hi: Bound::Closed(hi),
            ..self
        }
    }

    /// Whether `v` is finite and inside the interval.
    pub fn contains(&self, v: f64) -> bool {
        let lo_ok = match self.lo {
            Bound::Open(l) => v > l,
            Bound::Closed(l) => v >= l,
            Bound::None => true,
        };
        let hi_ok = match self.hi {
            Bound::Open(h) => v < h,
            Bound::Closed(h) => v <= h,
            Bound::None => true,
        };
        v.is_finite() && lo_ok && hi_ok
    }

    /// `v` if it is allowed, else the message `must be ..., got v` (callers add the name).
    pub fn check(&self, v: f64) -> Result<f64, String> {
        if self.contains(v) {
            Ok(v)
        } else {
            Err(format!("{self}, got {}", show(v)))
        }
    }

    /// `check` with the parameter's name in front: `rho: must be a number in [0, 1), got 1`.
    pub fn check_named(&self, name: &str, v: f64) -> Result<f64, String> {
        self.check(v).map_err(|m| format!("{name}: {m}"))
    }

    /// Parses text (what clap hands over) and checks it.
    pub fn parse(&self, text: &str) -> Result<f64, String> {
        let v: f64 = text
            .trim()
            .parse()
            .map_err(|_| format!("not a number; {self}"))?;
        if self.contains(v) {
            Ok(v)
        } else {
            Err(self.to_string())
        }
    }
}

/// A number in messages: plain for ordinary magnitudes, scientific beyond (f64::MAX is not printed
/// as 309 digits).
pub fn show(v: f64) -> String {
    if v == 0.0 || !v.is_finite() || (1e-4..1e9).contains(&v.abs()) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

impl fmt::Display for Real {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let unit = if self.unit.is_empty() {
            String::new()
        } else {
            format!(" {}", self.unit)
        };
        match (self.lo, self.hi) {
            (Bound::None, Bound::None) => write!(f, "must be a finite number{unit}"),
            (Bound::Closed(l), Bound::None) => {
                write!(f, "must be a finite number >= {}{unit}", show(l))
            }
            (Bound::Open(l), Bound::None) => {
                write!(f, "must be a finite number > {}{unit}", show(l))
            }
            (Bound::None, Bound::Closed(h)) => write!(f, "must be a number <= {}{unit}", show(h)),
            (Bound::None, Bound::Open(h)) => write!(f, "must be a number < {}{unit}", show(h)),
            (lo, hi) => {
                let (lb, l) = match lo {
                    Bound::Open(l) => ('(', l),
                    Bound::Closed(l) => ('[', l),
                    Bound::None => unreachable!("handled above"),
                };
                let (hb, h) = match hi {
                    Bound::Open(h) => (')', h),
                    Bound::Closed(h) => (']', h),
                    Bound::None => unreachable!("handled above"),
                };
                write!(
                    f,
                    "must be a number in {lb}{}, {}{hb}{unit}",
                    show(l),
                    show(h)
                )
            }
        }
    }
}

/// clap's error for a refused value: `invalid value 'X' for '--opt <V>': <why>`.
fn clap_error(
    cmd: &clap::Command,
    arg: Option<&clap::Arg>,
    value: &OsStr,
    why: String,
) -> clap::Error {
    let name = arg
        .map(|a| a.to_string())
        .unwrap_or_else(|| "value".to_string());
    let mut e = clap::Error::raw(
        clap::error::ErrorKind::ValueValidation,
        format!(
            "invalid value '{}' for '{name}': {why}\n",
            value.to_string_lossy()
        ),
    );
    e = e.with_cmd(cmd);
    e
}

impl clap::builder::TypedValueParser for Real {
    type Value = f64;
    fn parse_ref(
        &self,
        cmd: &clap::Command,
        arg: Option<&clap::Arg>,
        value: &OsStr,
    ) -> Result<f64, clap::Error> {
        let text = value.to_str().unwrap_or("");
        self.parse(text)
            .map_err(|why| clap_error(cmd, arg, value, why))
    }
}

/// A whole number in `[min, max]` converted to `T`, with a unit for messages (`"samples"`).
#[derive(Debug)]
pub struct Count<T> {
    min: u64,
    max: u64,
    unit: &'static str,
    _t: PhantomData<fn() -> T>,
}

impl<T> Clone for Count<T> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<T> Copy for Count<T> {}

impl<T> Count<T> {
    /// A whole number in `[min, max]`.
    pub const fn range(min: u64, max: u64, unit: &'static str) -> Count<T> {
        Count {
            min,
            max,
            unit,
            _t: PhantomData,
        }
    }
    /// A whole number >= 1 (up to `T`'s maximum, or 2^53 so that it stays exact in f64).
    pub const fn at_least_one(unit: &'static str) -> Count<T> {
        Count::range(1, 1 << 53, unit)
    }
    /// Whether `v` is in range.
    pub fn contains(&self, v: u64) -> bool {
        (self.min..=self.max).contains(&v)
    }
    /// `v` if it is allowed, else `must be a whole number in [min, max] unit, got v`.
    pub fn check(&self, v: u64) -> Result<u64, String> {
        if self.contains(v) {
            Ok(v)
        } else {
            Err(format!("{self}, got {v}"))
        }
    }
}

impl<T> fmt::Display for Count<T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let unit = if self.unit.is_empty() {
            String::new()
        } else {
            format!(" {}", self.unit)
        };
        if self.max == 1 << 53 {
            write!(f, "must be a whole number >= {}{unit}", self.min)
        } else {
            write!(
                f,
                "must be a whole number in [{}, {}]{unit}",
                self.min, self.max
            )
        }
    }
}

impl<T> clap::builder::TypedValueParser for Count<T>
where
    T: TryFrom<u64> + Clone + Send + Sync + 'static,
{
    type Value = T;
    fn parse_ref(
        &self,
        cmd: &clap::Command,
        arg: Option<&clap::Arg>,
        value: &OsStr,
    ) -> Result<T, clap::Error> {
        let text = value.to_str().unwrap_or("").trim();
        let v: u64 = text
            .parse()
            .map_err(|_| clap_error(cmd, arg, value, format!("not a whole number; {self}")))?;
        if !self.contains(v) {
            return Err(clap_error(cmd, arg, value, self.to_string()));
        }
        T::try_from(v).map_err(|_| clap_error(cmd, arg, value, self.to_string()))
    }
}

/// Worker threads: 0 means all cores (as does leaving the option out); at most 4096.
pub const THREADS: Count<usize> = Count::range(0, 4096, "threads (0: all cores)");

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser, Debug)]
    struct Args {
        #[arg(long, value_parser = Real::non_negative("m"))]
        near_radius: Option<f64>,
        #[arg(long, value_parser = Real::closed_open(0.0, 1.0, ""))]
        rho: Option<f64>,
        #[arg(long, value_parser = Count::<usize>::at_least_one("samples"))]
        samples: Option<usize>,
        #[arg(long, value_parser = THREADS)]
        threads: Option<usize>,
    }

    fn parse(args: &[&str]) -> Result<Args, String> {
        Args::try_parse_from(std::iter::once("x").chain(args.iter().copied()))
            .map_err(|e| e.render().to_string())
    }

    #[test]
    fn reals_refuse_nan_infinity_and_out_of_range_with_the_range_and_unit() {
        for (args, want) in [
            (
                &["--near-radius", "NaN"][..],
                "must be a finite number >= 0 m",
            ),
            (&["--near-radius=-0.1"], "must be a finite number >= 0 m"),
            (&["--near-radius", "inf"], "must be a finite number >= 0 m"),
            (&["--near-radius", "abc"], "not a number"),
            (&["--rho", "1"], "must be a number in [0, 1)"),
            (&["--rho=-0.5"], "must be a number in [0, 1)"),
            (&["--samples", "0"], "must be a whole number >= 1 samples"),
            (&["--samples=-3"], "not a whole number"),
            (&["--threads", "5000"], "[0, 4096]"),
        ] {
            let e = parse(args).unwrap_err();
            assert!(e.contains(want), "{args:?}: {e}");
            assert!(
                e.contains(args[0].split('=').next().unwrap()),
                "{args:?}: {e}"
            );
        }
        let a = parse(&["--near-radius", "0.25", "--rho", "0.999", "--samples", "7"]).unwrap();
        assert_eq!(a.near_radius, Some(0.25));
        assert_eq!(a.rho, Some(0.999));
        assert_eq!(a.samples, Some(7));
        assert_eq!(parse(&["--threads", "0"]).unwrap().threads, Some(0));
    }

    #[test]
    fn checks_and_display() {
        assert_eq!(
            Real::positive("lm").check_named("flux", -5.0).unwrap_err(),
            "flux: must be a finite number > 0 lm, got -5"
        );
        assert!(Real::positive("s")
            .at_most(1e7)
            .check(f64::INFINITY)
            .is_err());
        assert_eq!(Real::positive("s").at_most(1e7).check(3.0), Ok(3.0));
        assert_eq!(show(f64::MAX), "1.7976931348623157e308");
        assert_eq!(show(0.5), "0.5");
        assert_eq!(
            Real::open_closed(0.0, 1.0, "").to_string(),
            "must be a number in (0, 1]"
        );
        assert_eq!(
            Count::<u32>::range(1, 9, "").check(0).unwrap_err(),
            "must be a whole number in [1, 9], got 0"
        );
    }
}
