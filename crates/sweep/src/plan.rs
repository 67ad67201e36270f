//! Which points a sweep visits: a grid or seeded random samples over boxes
//! of parameter ranges, numbered so that any subset (a shard, the points
//! left after an interruption) can be computed independently.

use exact::Rational;
use rand::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;
use spec::ParamRange;

/// Largest number of points in one sweep.
pub const MAX_POINTS: u64 = 1 << 40;

/// How points are chosen.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sampling {
    /// The full tensor grid of the ranges (`COUNT` points each).
    Grid,
    /// `points` samples, uniform in the box of the ranges (`COUNT` unused).
    Random {
        /// How many.
        points: u64,
        /// The seed: the same seed gives the same points, in any shard.
        seed: u64,
    },
}

/// One shard of a sweep split across machines: the points whose index is
/// `k` modulo `n`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    /// This shard, `0 <= k < n`.
    pub k: u64,
    /// Number of shards.
    pub n: u64,
}

impl Shard {
    /// The whole sweep.
    pub const ALL: Shard = Shard { k: 0, n: 1 };

    /// Parse `K/N`. The error says what is expected and does not quote
    /// `text` (which may be huge): the caller quotes an excerpt of it.
    ///
    /// ```
    /// assert_eq!(sweep::Shard::parse("1/4").unwrap(), sweep::Shard { k: 1, n: 4 });
    /// assert!(sweep::Shard::parse("4/4").is_err());
    /// ```
    pub fn parse(text: &str) -> Result<Shard, PlanError> {
        let bad = || PlanError::BadShard;
        let (k, n) = text.split_once('/').ok_or_else(bad)?;
        let k: u64 = k.trim().parse().map_err(|_| bad())?;
        let n: u64 = n.trim().parse().map_err(|_| bad())?;
        if n == 0 || k >= n {
            return Err(bad());
        }
        Ok(Shard { k, n })
    }

    /// Whether point `index` belongs to this shard.
    pub fn contains(&self, index: u64) -> bool {
        index % self.n == self.k
    }
}

/// Why a plan or a shard could not be made.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum PlanError {
    /// No ranges at all.
    #[error(
        "nothing to sweep: give at least one --param NAME=START:STOP:COUNT (or ranges in the spec's sweep section)"
    )]
    Empty,
    /// The same parameter in two ranges.
    #[error("parameter '{0}' is swept twice")]
    SweptTwice(String),
    /// `--random 0`.
    #[error("--random needs at least one point")]
    NoRandomPoints,
    /// More than [`MAX_POINTS`].
    #[error("the sweep has more than {MAX_POINTS} points")]
    TooManyPoints,
    /// A shard that is not `K/N` with `0 <= K < N`.
    #[error("expected K/N with 0 <= K < N (for example 0/4)")]
    BadShard,
}

/// The points of a sweep.
#[derive(Clone, Debug, PartialEq)]
pub struct Plan {
    ranges: Vec<ParamRange>,
    sampling: Sampling,
    len: u64,
}

impl Plan {
    /// A plan over `ranges` (distinct names, at least one).
    ///
    /// ```
    /// use spec::ParamRange;
    /// let plan = sweep::Plan::new(
    ///     vec![ParamRange::parse("p=0:4:5").unwrap(), ParamRange::parse("mgl=0:1:3").unwrap()],
    ///     sweep::Sampling::Grid,
    /// ).unwrap();
    /// assert_eq!(plan.len(), 15);
    /// let last: Vec<String> = plan.point(14).iter().map(|r| r.to_string()).collect();
    /// assert_eq!(last, ["4", "1"]);
    /// ```
    pub fn new(ranges: Vec<ParamRange>, sampling: Sampling) -> Result<Plan, PlanError> {
        if ranges.is_empty() {
            return Err(PlanError::Empty);
        }
        for (i, r) in ranges.iter().enumerate() {
            if ranges[..i].iter().any(|q| q.name == r.name) {
                return Err(PlanError::SweptTwice(r.name.clone()));
            }
        }
        let len = match sampling {
            Sampling::Grid => ranges.iter().try_fold(1u64, |acc, r| acc.checked_mul(r.count)),
            Sampling::Random { points, .. } => Some(points),
        };
        let len = match len {
            Some(0) => return Err(PlanError::NoRandomPoints),
            Some(l) if l <= MAX_POINTS => l,
            _ => return Err(PlanError::TooManyPoints),
        };
        Ok(Plan { ranges, sampling, len })
    }

    /// The swept ranges, in order.
    pub fn ranges(&self) -> &[ParamRange] {
        &self.ranges
    }

    /// The sampling.
    pub fn sampling(&self) -> Sampling {
        self.sampling
    }

    /// Number of points.
    pub fn len(&self) -> u64 {
        self.len
    }

    /// Whether the plan is empty (never: [`Plan::new`] refuses that).
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The exact parameter values of point `index` (`< len`), one per range.
    /// On a grid the last range varies fastest.
    pub fn point(&self, index: u64) -> Vec<Rational> {
        match self.sampling {
            Sampling::Grid => {
                let mut rest = index;
                let mut out = vec![Rational::from_integer(0.into()); self.ranges.len()];
                for (slot, r) in out.iter_mut().zip(&self.ranges).rev() {
                    *slot = r.value(rest % r.count);
                    rest /= r.count;
                }
                out
            }
            Sampling::Random { seed, .. } => {
                // One generator per point, seeded from (seed, index): any
                // subset of the points is reproducible on its own.
                let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed ^ index.wrapping_mul(0x9E37_79B9_7F4A_7C15));
                self.ranges.iter().map(|r| r.fraction(rng.random_range(0..=(1u64 << 32)))).collect()
            }
        }
    }

    /// A text that identifies the plan (ranges and sampling, not the shard).
    pub fn describe(&self) -> String {
        let ranges: Vec<String> = self.ranges.iter().map(ParamRange::to_text).collect();
        match self.sampling {
            Sampling::Grid => format!("grid {}", ranges.join(" ")),
            Sampling::Random { points, seed } => format!("random {points} seed {seed} {}", ranges.join(" ")),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_visits_every_combination_once() {
        let plan = Plan::new(
            vec![ParamRange::parse("a=0:1:3").unwrap(), ParamRange::parse("b=1/2:3/2:2").unwrap()],
            Sampling::Grid,
        )
        .unwrap();
        let mut seen: Vec<String> = (0..plan.len())
            .map(|i| plan.point(i).iter().map(|r| r.to_string()).collect::<Vec<_>>().join(","))
            .collect();
        seen.sort();
        seen.dedup();
        assert_eq!(seen, ["0,1/2", "0,3/2", "1,1/2", "1,3/2", "1/2,1/2", "1/2,3/2"]);
    }

    #[test]
    fn random_points_lie_in_the_box_and_repeat_with_the_seed() {
        let ranges = vec![ParamRange::parse("a=-1:2:9").unwrap(), ParamRange::parse("b=0:1/1000:9").unwrap()];
        let plan = Plan::new(ranges.clone(), Sampling::Random { points: 500, seed: 7 }).unwrap();
        let again = Plan::new(ranges.clone(), Sampling::Random { points: 500, seed: 7 }).unwrap();
        let other = Plan::new(ranges, Sampling::Random { points: 500, seed: 8 }).unwrap();
        let lo = [Rational::new((-1).into(), 1.into()), Rational::from_integer(0.into())];
        let hi = [Rational::from_integer(2.into()), Rational::new(1.into(), 1000.into())];
        let mut differs = 0;
        for i in 0..500 {
            let p = plan.point(i);
            assert_eq!(p, again.point(i));
            differs += usize::from(p != other.point(i));
            for d in 0..2 {
                assert!(p[d] >= lo[d] && p[d] <= hi[d], "{p:?}");
            }
        }
        assert!(differs > 490);
    }

    #[test]
    fn oversized_and_empty_plans_are_refused() {
        let big = |n: &str| ParamRange::parse(&format!("{n}=0:1:1000000000")).unwrap();
        let err = Plan::new(vec![big("a"), big("b"), big("c")], Sampling::Grid).unwrap_err();
        assert_eq!(err, PlanError::TooManyPoints);
        assert!(err.to_string().contains("more than"), "{err}");
        assert_eq!(Plan::new(vec![], Sampling::Grid).unwrap_err(), PlanError::Empty);
        let a = ParamRange::parse("a=0:1:2").unwrap();
        assert_eq!(
            Plan::new(vec![a.clone(), a.clone()], Sampling::Grid).unwrap_err(),
            PlanError::SweptTwice("a".into())
        );
        assert_eq!(Plan::new(vec![a], Sampling::Random { points: 0, seed: 1 }).unwrap_err(), PlanError::NoRandomPoints);
    }
}
