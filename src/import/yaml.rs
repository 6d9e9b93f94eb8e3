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

/// A YAML document refused at a place: its syntax, or a bound.
#[derive(Debug, Clone, PartialEq)]
pub struct SyntaxError {
    pub at: At,
    pub message: String,
}

/// Largest number of nodes a document may expand to, every use of an alias counted with its
/// whole value (a file of nested aliases had expanded to gigabytes).
pub const MAX_YAML_NODES: usize = 1_000_000;

/// Deepest nesting of sequences and mappings.
pub const MAX_YAML_DEPTH: usize = 256;

/// Parses one YAML document (an empty text is `Null`); a second document, an expansion beyond
/// [`MAX_YAML_NODES`] or nesting beyond [`MAX_YAML_DEPTH`] is an error at its place.
pub fn parse(text: &str) -> Result<Yaml, SyntaxError> {
    let mut b = Builder::default();
    let mut parser = Parser::new_from_str(text);
    parser
        .load(&mut b, true)
        .map_err(|e| SyntaxError { at: at(e.marker()), message: format!("YAML syntax: {}", e.info()) })?;
    if let Some(e) = b.error {
        return Err(e);
    }
    Ok(b.root.unwrap_or(Yaml::Null(At { line: 1, col: 1 })))
}

fn at(m: &Marker) -> At {
    At { line: m.line(), col: m.col() + 1 }
}

/// Builds the tree from the parser's events: a stack of open collections, each with its anchor
/// and the node count when it opened.
#[derive(Default)]
struct Builder {
    stack: Vec<(Yaml, usize, usize)>,
    /// Pending key of each open mapping.
    keys: Vec<Option<Yaml>>,
    /// Each anchored value with its number of nodes.
    anchors: std::collections::BTreeMap<usize, (Yaml, usize)>,
    root: Option<Yaml>,
    /// Nodes made so far (aliases counted with their whole value).
    nodes: usize,
    documents: usize,
    /// The first reason to stop; every later event is ignored.
    error: Option<SyntaxError>,
}

impl Builder {
    fn push_value(&mut self, v: Yaml, anchor: usize, size: usize) {
        if anchor > 0 {
            self.anchors.insert(anchor, (v.clone(), size));
        }
        match self.stack.last_mut() {
            None => self.root = Some(v),
            Some((Yaml::Seq(items, _), ..)) => items.push(v),
            Some((Yaml::Map(kv, _), ..)) => {
                let slot = self.keys.last_mut().expect("a key slot per open mapping");
                match slot.take() {
                    None => *slot = Some(v),
                    Some(k) => kv.push((k, v)),
                }
            }
            Some(_) => {}
        }
    }

    /// Counts `size` more nodes, or stops at the limit.
    fn count(&mut self, size: usize, a: At) -> bool {
        self.nodes += size;
        if self.nodes > MAX_YAML_NODES {
            self.stop(
                a,
                format!("the document expands to more than {MAX_YAML_NODES} nodes (aliases counted at every use)"),
            );
        }
        self.error.is_none()
    }

    fn stop(&mut self, a: At, message: String) {
        self.error.get_or_insert(SyntaxError { at: a, message });
    }

    /// Opens a sequence or mapping, within [`MAX_YAML_DEPTH`].
    fn open(&mut self, v: Yaml, anchor: usize, a: At) {
        if self.stack.len() == MAX_YAML_DEPTH {
            return self.stop(a, format!("sequences and mappings nested deeper than {MAX_YAML_DEPTH}"));
        }
        if self.count(1, a) {
            let is_map = matches!(v, Yaml::Map(..));
            self.stack.push((v, anchor, self.nodes - 1));
            if is_map {
                self.keys.push(None);
            }
        }
    }
}

impl MarkedEventReceiver for Builder {
    fn on_event(&mut self, ev: Event, mark: Marker) {
        let a = at(&mark);
        if self.error.is_some() {
            return;
        }
        match ev {
            Event::DocumentStart => {
                self.documents += 1;
                if self.documents > 1 {
                    self.stop(a, "a second YAML document: an import reads one document per file".into());
                }
            }
            Event::Scalar(s, style, anchor, _) => {
                let plain = matches!(style, yaml_rust2::scanner::TScalarStyle::Plain);
                let v =
                    if plain && (s == "~" || s == "null" || s.is_empty()) { Yaml::Null(a) } else { Yaml::Scalar(s, a) };
                if self.count(1, a) {
                    self.push_value(v, anchor, 1);
                }
            }
            Event::SequenceStart(anchor, _) => self.open(Yaml::Seq(Vec::new(), a), anchor, a),
            Event::MappingStart(anchor, _) => self.open(Yaml::Map(Vec::new(), a), anchor, a),
            Event::SequenceEnd | Event::MappingEnd => {
                if let Some((v, anchor, opened)) = self.stack.pop() {
                    if matches!(v, Yaml::Map(..)) {
                        self.keys.pop();
                    }
                    self.push_value(v, anchor, self.nodes - opened);
                }
            }
            Event::Alias(id) => {
                let size = self.anchors.get(&id).map_or(1, |(_, n)| *n);
                if self.count(size, a) {
                    let v = self.anchors.get(&id).map_or(Yaml::Null(a), |(v, _)| v.clone());
                    self.push_value(v, 0, size);
                }
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
