//! A YAML document as a tree whose every node keeps its line and column, so that an import can
//! say where a value it rejects is (`file.yaml:LINE:COL`). Read with yaml-rust2's event parser
//! (anchors and aliases resolved; tags ignored).

use yaml_rust2::parser::{Event, MarkedEventReceiver, Parser};
use yaml_rust2::scanner::Marker;

/// Line and column (both from 1) of a YAML node.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct At {
    pub line: usize,
    pub col: usize,
}

#[derive(Clone, Debug, PartialEq)]
pub enum Yaml {
    /// A scalar as written (numbers are parsed where a number is expected).
    Scalar(String, At),
    Seq(Vec<Yaml>, At),
    /// Key-value pairs in file order.
    Map(Vec<(Yaml, Yaml)>, At),
    /// An empty document or a `~`/`null` value.
    Null(At),
}

impl Yaml {
    pub fn at(&self) -> At {
        match self {
            Yaml::Scalar(_, a) | Yaml::Seq(_, a) | Yaml::Map(_, a) | Yaml::Null(a) => *a,
        }
    }

    /// The value of `key` in a mapping.
    pub fn get(&self, key: &str) -> Option<&Yaml> {
        match self {
            Yaml::Map(kv, _) => kv.iter().find(|(k, _)| k.as_str() == Some(key)).map(|(_, v)| v),
            _ => None,
        }
    }

    pub fn as_str(&self) -> Option<&str> {
        match self {
            Yaml::Scalar(s, _) => Some(s),
            _ => None,
        }
    }
}

/// A YAML syntax error at a place.
#[derive(Debug, Clone, PartialEq)]
pub struct SyntaxError {
    pub at: At,
    pub message: String,
}

/// Parses one YAML document (an empty text is `Null`).
pub fn parse(text: &str) -> Result<Yaml, SyntaxError> {
    let mut b = Builder::default();
    let mut parser = Parser::new_from_str(text);
    parser.load(&mut b, false).map_err(|e| SyntaxError { at: at(e.marker()), message: e.info().to_string() })?;
    Ok(b.root.unwrap_or(Yaml::Null(At { line: 1, col: 1 })))
}

fn at(m: &Marker) -> At {
    At { line: m.line(), col: m.col() + 1 }
}

/// Builds the tree from the parser's events: a stack of open collections.
#[derive(Default)]
struct Builder {
    stack: Vec<(Yaml, usize)>,
    /// Pending key of each open mapping.
    keys: Vec<Option<Yaml>>,
    anchors: std::collections::BTreeMap<usize, Yaml>,
    root: Option<Yaml>,
}

impl Builder {
    fn push_value(&mut self, v: Yaml, anchor: usize) {
        if anchor > 0 {
            self.anchors.insert(anchor, v.clone());
        }
        match self.stack.last_mut() {
            None => self.root = Some(v),
            Some((Yaml::Seq(items, _), _)) => items.push(v),
            Some((Yaml::Map(kv, _), _)) => {
                let slot = self.keys.last_mut().expect("a key slot per open mapping");
                match slot.take() {
                    None => *slot = Some(v),
                    Some(k) => kv.push((k, v)),
                }
            }
            Some(_) => {}
        }
    }
}

impl MarkedEventReceiver for Builder {
    fn on_event(&mut self, ev: Event, mark: Marker) {
        let a = at(&mark);
        match ev {
            Event::Scalar(s, style, anchor, _) => {
                let plain = matches!(style, yaml_rust2::scanner::TScalarStyle::Plain);
                let v =
                    if plain && (s == "~" || s == "null" || s.is_empty()) { Yaml::Null(a) } else { Yaml::Scalar(s, a) };
                self.push_value(v, anchor);
            }
            Event::SequenceStart(anchor, _) => self.stack.push((Yaml::Seq(Vec::new(), a), anchor)),
            Event::MappingStart(anchor, _) => {
                self.stack.push((Yaml::Map(Vec::new(), a), anchor));
                self.keys.push(None);
            }
            Event::SequenceEnd | Event::MappingEnd => {
                if let Some((v, anchor)) = self.stack.pop() {
                    if matches!(v, Yaml::Map(..)) {
                        self.keys.pop();
                    }
                    self.push_value(v, anchor);
                }
            }
            Event::Alias(id) => {
                let v = self.anchors.get(&id).cloned().unwrap_or(Yaml::Null(a));
                self.push_value(v, 0);
            }
            _ => {}
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn maps_sequences_and_places() {
        let y = parse("nodes:\n  a: [1, 2.5, -3]\npairs:\n  - [a, b]\n").unwrap();
        let nodes = y.get("nodes").unwrap();
        let Yaml::Seq(xs, at) = nodes.get("a").unwrap() else { panic!() };
        assert_eq!(xs.iter().map(|x| x.as_str().unwrap()).collect::<Vec<_>>(), ["1", "2.5", "-3"]);
        assert_eq!(*at, At { line: 2, col: 6 });
        assert_eq!(y.get("pairs").unwrap().at().line, 4);
        let e = parse("a: [1, 2\n").unwrap_err();
        assert!(e.at.line >= 1, "{e:?}");
    }
}
