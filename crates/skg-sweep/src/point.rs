//! One point of a sweep and how it is named: its [`Method`] (the action solved, or the
//! time-stepping peer), its values as written, its canonical text and id, the scene
//! overrides it stands for ([`Point::overrides`]); and the [`Shard`] `k/n` that owns
//! the points whose index is `k−1 mod n`.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use skg_core::scene::{Backend, Formulation, GridChoice, HessianMode, InitialVelocity, Overrides, Stepper};

use crate::AxisError;

/// Axes that are not scene parameters.
pub const SETTING_AXES: &[&str] =
    &["nodes", "operator", "formulation", "initial_velocity", "hessian", "max_iter", "backend", "verify_tol", "stepper", "grid"];

/// How a point is computed.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub enum Method {
    /// The SKG action solved by the scene's backend (Ipopt by default).
    Skg,
    /// The time-stepping reference integrator (DOP853, [`skg_core::stepping::reference::regularized`])
    /// at a relative tolerance (absolute tolerance the same).
    Ode {
        /// Relative (and absolute) tolerance.
        rtol: f64,
    },
}

impl Method {
    /// The `method` column: `skg` or `ode`.
    pub fn name(&self) -> &'static str {
        match self {
            Method::Skg => "skg",
            Method::Ode { .. } => "ode",
        }
    }
}

/// One point of a sweep.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct Point {
    /// Position in the expanded sweep (0-based).
    pub index: usize,
    /// Axis name → value as written (canonical text).
    pub values: Vec<(String, String)>,
    /// Axis name → value in the resolved scene, for the scene-parameter axes (`1/110` →
    /// 0.00909…), filled by [`SweepFile::expand`](crate::SweepFile::expand). Not part of the id.
    #[serde(default)]
    pub evaluated: Vec<(String, f64)>,
    /// How the point is computed.
    pub method: Method,
}

impl Point {
    /// Canonical text: `method` first, then the axes sorted by name.
    pub fn canonical(&self) -> String {
        let mut parts = vec![match &self.method {
            Method::Skg => format!("method={}", self.method.name()),
            Method::Ode { rtol } => format!("method={};rtol={rtol:?}", self.method.name()),
        }];
        let sorted: BTreeMap<&str, &str> = self.values.iter().map(|(k, v)| (k.as_str(), v.as_str())).collect();
        parts.extend(sorted.iter().map(|(k, v)| format!("{k}={v}")));
        parts.join(";")
    }

    /// Stable id: FNV-1a 64 of the canonical text, as 16 hex digits.
    pub fn id(&self) -> String {
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        for b in self.canonical().bytes() {
            h ^= b as u64;
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
        format!("{h:016x}")
    }

    /// The value of an axis as written, if the point sets it.
    pub fn value(&self, axis: &str) -> Option<&str> {
        self.values.iter().find(|(k, _)| k == axis).map(|(_, v)| v.as_str())
    }

    /// The value of a scene-parameter axis in the resolved scene (see [`Point::evaluated`]).
    pub fn evaluated(&self, axis: &str) -> Option<f64> {
        self.evaluated.iter().find(|(k, _)| k == axis).map(|&(_, v)| v)
    }

    /// The scene overrides this point stands for.
    pub fn overrides(&self) -> Result<Overrides, AxisError> {
        let mut ov = Overrides::default();
        for (k, v) in &self.values {
            let whole = |axis: &'static str| move |_| AxisError::WholeNumber { axis, value: v.clone() };
            match k.as_str() {
                "nodes" => ov.nodes = Some(v.parse().map_err(whole("nodes"))?),
                "operator" if v.trim().eq_ignore_ascii_case("auto") => ov.auto_operator = true,
                "operator" => ov.operator = Some(v.parse().map_err(|error| AxisError::Operator { value: v.clone(), error })?),
                "verify_tol" => {
                    let tol: f64 = v.trim().parse().map_err(|_| AxisError::VerifyTol { value: v.clone() })?;
                    if !(tol > 0.0 && tol.is_finite()) {
                        return Err(AxisError::VerifyTol { value: v.clone() });
                    }
                    ov.verify_tol = Some(tol);
                }
                "formulation" => ov.formulation = Some(v.parse::<Formulation>()?),
                "initial_velocity" => ov.initial_velocity = Some(v.parse::<InitialVelocity>()?),
                "hessian" => {
                    ov.hessian = Some(match v.to_ascii_lowercase().as_str() {
                        "zero" => HessianMode::Zero,
                        "exact" => HessianMode::Exact,
                        _ => return Err(AxisError::Hessian { value: v.clone() }),
                    })
                }
                "max_iter" => ov.max_iter = Some(v.parse().map_err(whole("max_iter"))?),
                "backend" => ov.backend = Some(v.parse::<Backend>()?),
                "stepper" => ov.stepper = Some(v.parse::<Stepper>()?),
                "grid" => ov.grid = Some(v.parse::<GridChoice>()?),
                _ => ov.set.push((k.clone(), v.clone())),
            }
        }
        Ok(ov)
    }
}

/// A shard `k/n` (1-based k).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// This shard's number, 1 ≤ k ≤ n.
    pub k: usize,
    /// The number of shards.
    pub n: usize,
}

/// A shard that is not `k/n` with 1 ≤ k ≤ n.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("bad shard `{input}`: expected k/n with 1 ≤ k ≤ n, e.g. 2/8")]
pub struct ParseShardError {
    /// The rejected input.
    pub input: String,
}

impl std::str::FromStr for Shard {
    type Err = ParseShardError;
    fn from_str(s: &str) -> Result<Self, ParseShardError> {
        let bad = || ParseShardError { input: s.to_string() };
        let (k, n) = s.split_once('/').ok_or_else(bad)?;
        let (k, n): (usize, usize) = (k.trim().parse().map_err(|_| bad())?, n.trim().parse().map_err(|_| bad())?);
        if n == 0 || k == 0 || k > n {
            return Err(bad());
        }
        Ok(Shard { k, n })
    }
}

impl Shard {
    /// Whether the point with this index belongs to the shard.
    pub fn contains(&self, index: usize) -> bool {
        index % self.n == self.k - 1
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::csv_line;

    #[test]
    fn shard_parsing() {
        assert_eq!("2/8".parse::<Shard>(), Ok(Shard { k: 2, n: 8 }));
        for bad in ["0/3", "4/3", "1/0", "x/2", "3"] {
            assert!(bad.parse::<Shard>().is_err(), "{bad}");
        }
        let s = Shard { k: 2, n: 3 };
        assert!(s.contains(1) && s.contains(4) && !s.contains(0));
    }

    #[test]
    fn id_ignores_axis_order_and_csv_line_is_one_line() {
        let values = vec![("nodes".into(), "64".into()), ("sigma".into(), "1/110".into())];
        let a = Point { index: 0, values, evaluated: vec![("sigma".into(), 1.0 / 110.0)], method: Method::Skg };
        let mut b = a.clone();
        b.values.reverse();
        b.index = 7;
        assert_eq!(a.id(), b.id());
        assert_eq!(a.canonical(), "method=skg;nodes=64;sigma=1/110");
        let line = csv_line(&["a,b".into(), "x\"y".into(), "".into()]);
        assert_eq!(String::from_utf8(line).unwrap(), "\"a,b\",\"x\"\"y\",\n");
    }
}
