//! Parameters: numbers or expressions of other parameters, evaluated in dependency
//! order with the overrides applied, and the evaluation of every number-or-expression
//! of a scene file.

use indexmap::IndexMap;
use skg_expr::{Graph, ParseError, Symbol};
use toml::Spanned;

use super::error::SceneError;
use super::file::{NumOrExpr, SceneFile};
use super::names::TIME;

/// A scene's parameter values and their definitions (the file's, or an override's).
pub(super) type ResolvedParameters = (IndexMap<String, f64>, IndexMap<String, NumOrExpr>);

impl SceneFile {
    /// Evaluate a number-or-expression in terms of resolved parameters.
    pub fn eval_value(&self, v: &Spanned<NumOrExpr>, key: &str, params: &IndexMap<String, f64>) -> Result<f64, SceneError> {
        let value = match v.get_ref() {
            NumOrExpr::Num(x) => *x,
            NumOrExpr::Expr(s) => {
                let spanned = Spanned::new(v.span(), s.clone());
                eval_constant(s, params).map_err(|e| self.expression_error(&spanned, key, e))?
            }
        };
        if !value.is_finite() {
            return Err(self.invalid(v, format!("`{key}` is not finite ({value})")));
        }
        Ok(value)
    }

    /// Evaluate parameters in dependency order (each may use the others); overrides
    /// replace a declared parameter's definition. Returns the values and the definitions
    /// they were evaluated from, both in declaration order.
    pub(super) fn resolve_parameters(&self, set: &[(String, String)]) -> Result<ResolvedParameters, SceneError> {
        let mut defs: IndexMap<String, (NumOrExpr, Option<&Spanned<NumOrExpr>>)> =
            self.parameters.iter().map(|(k, v)| (k.clone(), (v.get_ref().clone(), Some(v)))).collect();
        for (name, value) in set {
            if !defs.contains_key(name) {
                let known: Vec<&str> = self.parameters.keys().map(String::as_str).collect();
                return Err(SceneError::Override {
                    assignment: format!("{name}={value}"),
                    message: format!(
                        "the scene has no parameter `{name}` (parameters: {})",
                        if known.is_empty() { "none".to_string() } else { known.join(", ") }
                    ),
                });
            }
            let v = match value.parse::<f64>() {
                Ok(x) => NumOrExpr::Num(x),
                Err(_) => NumOrExpr::Expr(value.clone()),
            };
            defs.insert(name.clone(), (v, None));
        }
        let mut values: IndexMap<String, f64> = IndexMap::new();
        let mut pending: Vec<&String> = defs.keys().collect();
        while !pending.is_empty() {
            let mut progressed = false;
            let mut still = Vec::new();
            for name in pending {
                let (def, spanned) = &defs[name];
                let result = match def {
                    NumOrExpr::Num(x) => Ok(*x),
                    NumOrExpr::Expr(s) => eval_constant(s, &values),
                };
                match result {
                    Ok(x) => {
                        if !x.is_finite() {
                            return Err(self.param_error(name, spanned, format!("parameter `{name}` is not finite ({x})")));
                        }
                        values.insert(name.clone(), x);
                        progressed = true;
                    }
                    Err(_) => still.push(name),
                }
            }
            if !progressed {
                // Report the first failing one with its real error (unknown name or syntax).
                let name = still[0];
                let (def, spanned) = &defs[name];
                let NumOrExpr::Expr(s) = def else { unreachable!("numbers always resolve") };
                let mut err = match eval_constant(s, &values) {
                    Err(e) => e,
                    Ok(_) => unreachable!("expression failed a moment ago"),
                };
                let names: Vec<&str> = defs.keys().map(String::as_str).collect();
                // A cycle when the unknown symbol is itself an unresolved parameter.
                if err.message.contains("unknown") && still.iter().any(|n| err.message.contains(&format!("`{n}`"))) {
                    err.message = format!(
                        "{} (parameters that depend on each other in a cycle: {})",
                        err.message,
                        still.iter().map(|s| s.as_str()).collect::<Vec<_>>().join(", ")
                    );
                } else if err.message.contains("unknown") {
                    err.message = format!("{} (parameters: {})", err.message, names.join(", "));
                }
                return Err(match spanned {
                    Some(v) => {
                        let sp = Spanned::new(v.span(), s.clone());
                        self.expression_error(&sp, &format!("parameters.{name}"), err)
                    }
                    None => SceneError::Override { assignment: format!("{name}={s}"), message: format!("{}\n{}", err, err.caret_line()) },
                });
            }
            pending = still;
        }
        // Keep the declaration order.
        let definitions = defs.iter().map(|(k, (def, _))| (k.clone(), def.clone())).collect();
        Ok((defs.keys().map(|k| (k.clone(), values[k])).collect(), definitions))
    }

    fn param_error(&self, name: &str, spanned: &Option<&Spanned<NumOrExpr>>, message: String) -> SceneError {
        match spanned {
            Some(v) => self.invalid(v, message),
            None => SceneError::Override { assignment: name.to_string(), message },
        }
    }
}

/// Evaluate an expression that may use only parameters (already resolved) and `pi`.
/// The time `t` is unknown here, with a hint that says why.
pub fn eval_constant(src: &str, params: &IndexMap<String, f64>) -> Result<f64, ParseError> {
    let mut g = Graph::new();
    let mut asked_for_time = false;
    let e = g
        .parse(src, &mut |name| {
            asked_for_time |= name == TIME;
            params.get(name).map(|v| Symbol::Const(*v))
        })
        .map_err(|e| {
            // An unknown name stops the parse at once, so the time was the unknown name.
            if asked_for_time {
                e.with_hint(
                    "the time `t` may appear in the Lagrangian, constraints, forces and walls only; \
                     parameters, initial values and the numbers of [[walls]] and [time] are constants",
                )
            } else {
                e
            }
        })?;
    Ok(g.eval(e, &[]))
}
