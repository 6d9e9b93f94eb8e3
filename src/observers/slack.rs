//! Cable slackness, tick by tick: the intervals of ticks in which each cable carried no
//! tension.

use super::{Made, Note, Observer, Setup, Tick};
use crate::report::{ScenarioReport, SlackInterval};

#[derive(Default)]
pub struct SlackTracker {
    /// Per cable: the open interval (first, last tick) while slack.
    open: Vec<Option<(u64, u64)>>,
    names: Vec<String>,
    closed: Vec<SlackInterval>,
}

impl SlackTracker {
    pub fn new() -> Self {
        Self::default()
    }

    /// Every interval so far, the open ones closed at their last tick.
    pub fn intervals(&self) -> Vec<SlackInterval> {
        let mut out = self.closed.clone();
        for (c, iv) in self.open.iter().enumerate() {
            if let Some((first, last)) = iv {
                out.push(SlackInterval { cable: self.names[c].clone(), first_tick: *first, last_tick: *last });
            }
        }
        out.sort_by(|a, b| (a.first_tick, &a.cable).cmp(&(b.first_tick, &b.cable)));
        out
    }
}

/// Every run tracks its cables' slack (`observers::KINDS`).
pub(super) fn make(_setup: &Setup, _warnings: &mut Vec<String>) -> Made {
    Ok(Some(Box::new(SlackTracker::new())))
}

impl Observer for SlackTracker {
    fn tick(&mut self, t: &Tick, notes: &mut Vec<Note>) {
        let slack = &t.snapshot.forces.slack;
        if self.open.len() != slack.len() {
            self.open = vec![None; slack.len()];
            self.names = t.structure.members.iter().map(|c| c.name.clone()).collect();
        }
        let tick = t.snapshot.tick;
        for (c, &is_slack) in slack.iter().enumerate() {
            match (&mut self.open[c], is_slack) {
                (Some(iv), true) => iv.1 = tick,
                (None, true) => {
                    self.open[c] = Some((tick, tick));
                    notes.push(Note::Event(format!("cable {} went slack", self.names[c])));
                }
                (Some((first, last)), false) => {
                    self.closed.push(SlackInterval {
                        cable: self.names[c].clone(),
                        first_tick: *first,
                        last_tick: *last,
                    });
                    self.open[c] = None;
                    notes.push(Note::Event(format!("cable {} went taut", self.names[c])));
                }
                (None, false) => {}
            }
        }
    }

    fn finish(&mut self, report: &mut ScenarioReport) {
        report.slack_intervals = self.intervals();
    }
}
