//! Which kind of path the steps take: a settle accelerator (the static relaxation, the Newton
//! damping schedule) makes a step no part of a physical path; after
//! [`super::Simulation::end_acceleration`] every step is physical.

/// Whether the steps are physical for good, and how many took an accelerator.
#[derive(Clone, Default)]
pub(super) struct Path {
    /// Only the physical dynamics from now on: no static relaxation, no Newton damping
    /// schedule, every joint's damping as stated.
    pub(super) physical: bool,
    /// Whether the last step took a settle accelerator (the relaxation or the Newton schedule).
    pub(super) last_step_accelerated: bool,
    /// Steps taken with a settle accelerator.
    pub(super) accelerated_steps: u64,
}

impl Path {
    /// Notes a step, `accelerated` when it took a settle accelerator.
    pub(super) fn note_step(&mut self, accelerated: bool) {
        self.last_step_accelerated = accelerated;
        self.accelerated_steps += u64::from(accelerated);
    }
}
