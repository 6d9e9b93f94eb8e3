//! The whole test suite as one binary (one link of rapier and the rerun SDK instead of one
//! per file): each file beside this one is a module, `common.rs` their shared helpers.

mod architecture;
mod bad_input;
mod bench;
mod bench_scale;
mod cli;
mod common;
mod compact_members;
mod custom_structure;
mod export_mjcf;
mod figures;
mod furet2018_dynamics;
mod fuzz_scenarios;
mod import_matrices;
mod import_ntrt;
mod interference;
mod interrupts;
mod ji2014_dynamics;
mod joint_probe;
mod joint_settling;
mod manriquez2019_dynamics;
mod model_expressions;
mod model_scenarios;
mod mohr2011_dynamics;
mod motion;
mod moved_node;
mod outputs;
mod param_sweep;
mod recording;
mod relaxation;
mod restart;
mod shipped_scenarios;
mod sim_divergence;
mod sweep;
mod table;
mod verdicts;
