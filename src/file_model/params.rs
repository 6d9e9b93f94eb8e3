//! A file's `[params]` as a table that can be evaluated again with some parameters set to
//! other values: how a sweep over parameters (`actuation.grid = { k1 = {...} }`) gets, at
//! each point, every parameter that depends on the swept ones (`ratio = "k1/k2"`).

use super::expr::Expr;
use crate::mechanisms::Values;

/// One parameter: a number, or an expression of the parameters before it in
/// [`ParamTable::order`].
#[derive(Clone, Debug)]
enum Definition {
    Number(f64),
    // Boxed: an expression is some 19 kB, a number 8 bytes.
    Expr(Box<Expr>),
}

/// The file's parameters in an order in which each expression's parameters come before it.
#[derive(Clone, Debug, Default)]
pub struct ParamTable {
    /// Parameter names, in the file's order (the expressions' symbol indices).
    names: Vec<String>,
    definitions: Vec<Definition>,
    /// Indices into `names`, in evaluation order.
    order: Vec<usize>,
}

/// A parameter that depends on itself through others: its index.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cycle(pub usize);

impl ParamTable {
    /// The table of `names`, each a number (`Ok`) or an expression compiled against `names`
    /// (`Err` holds it); a cycle names its first parameter.
    pub fn new(names: Vec<String>, definitions: Vec<Result<f64, Expr>>) -> Result<ParamTable, Cycle> {
        let definitions: Vec<Definition> = definitions
            .into_iter()
            .map(|d| match d {
                Ok(x) => Definition::Number(x),
                Err(e) => Definition::Expr(Box::new(e)),
            })
            .collect();
        let mut order = Vec::with_capacity(names.len());
        let mut done = vec![false; names.len()];
        // Take whatever is ready, as many rounds as there are parameters.
        for _ in 0..=names.len() {
            for (i, d) in definitions.iter().enumerate() {
                let ready = match d {
                    Definition::Number(_) => true,
                    Definition::Expr(e) => e.uses().iter().all(|u| done[*u]),
                };
                if !done[i] && ready {
                    done[i] = true;
                    order.push(i);
                }
            }
        }
        match done.iter().position(|d| !d) {
            Some(i) => Err(Cycle(i)),
            None => Ok(ParamTable { names, definitions, order }),
        }
    }

    /// Whether `name` is a parameter of the file.
    pub fn has(&self, name: &str) -> bool {
        self.names.iter().any(|n| n == name)
    }

    /// Whether `name` is a derived parameter: an expression of others, which follows them (an
    /// expression of numbers alone, `pi/10`, is not).
    pub fn is_derived(&self, name: &str) -> bool {
        let at = self.names.iter().position(|n| n == name);
        at.is_some_and(|i| matches!(&self.definitions[i], Definition::Expr(e) if !e.uses().is_empty()))
    }

    /// The parameters that nothing reaches: neither `read` (what reads a parameter by name
    /// outside the table) nor the expression of a reached parameter (derived ones are walked
    /// back to what they derive from, in reverse evaluation order).
    pub fn unreached(&self, read: impl Fn(&str) -> bool) -> Vec<String> {
        let mut reached: Vec<bool> = self.names.iter().map(|n| read(n)).collect();
        for &i in self.order.iter().rev() {
            if let (true, Definition::Expr(e)) = (reached[i], &self.definitions[i]) {
                for &u in e.uses() {
                    reached[u] = true;
                }
            }
        }
        self.names.iter().zip(reached).filter(|(_, r)| !r).map(|(n, _)| n.clone()).collect()
    }

    /// Every parameter's value, those named in `set` taking the given value instead of their
    /// definition (the others that depend on them follow).
    pub fn evaluate(&self, set: &Values) -> Values {
        let mut values = vec![f64::NAN; self.names.len()];
        for &i in &self.order {
            values[i] = match (set.get(&self.names[i]), &self.definitions[i]) {
                (Some(x), _) => *x,
                (None, Definition::Number(x)) => *x,
                (None, Definition::Expr(e)) => e.eval(&values),
            };
        }
        self.names.iter().cloned().zip(values).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table() -> ParamTable {
        let names: Vec<String> = ["ratio", "k1", "k2"].iter().map(|s| s.to_string()).collect();
        let refs: Vec<&str> = names.iter().map(String::as_str).collect();
        let ratio = Expr::compile("k1/k2", &refs).unwrap();
        ParamTable::new(names, vec![Err(ratio), Ok(50.0), Ok(20.0)]).unwrap()
    }

    #[test]
    fn a_derived_parameter_follows_the_swept_one() {
        let t = table();
        assert!((t.evaluate(&Values::new())["ratio"] - 2.5).abs() < 1e-15);
        let set: Values = [("k1".to_string(), 80.0)].into();
        let v = t.evaluate(&set);
        assert!((v["ratio"] - 4.0).abs() < 1e-15);
        assert_eq!(v["k2"], 20.0);
    }

    #[test]
    fn what_a_read_parameter_derives_from_is_reached() {
        let t = table();
        assert_eq!(t.unreached(|n| n == "ratio"), Vec::<String>::new());
        assert_eq!(t.unreached(|n| n == "k2"), vec!["ratio".to_string(), "k1".to_string()]);
    }

    #[test]
    fn a_parameter_that_needs_itself_is_a_cycle() {
        let names: Vec<String> = ["a", "b"].iter().map(|s| s.to_string()).collect();
        let refs: Vec<&str> = names.iter().map(String::as_str).collect();
        let a = Expr::compile("2*b", &refs).unwrap();
        let b = Expr::compile("a+1", &refs).unwrap();
        assert_eq!(ParamTable::new(names, vec![Err(a), Err(b)]).unwrap_err(), Cycle(0));
    }
}
