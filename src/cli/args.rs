//! The command line's grammar: every subcommand and flag (clap derive), parsed and nothing
//! else. What each command does is in its own file beside this one.

use crate::import::matrices::MatrixOptions;
use clap::{Parser, Subcommand};
use std::path::PathBuf;

/// The MuJoCo peer of `benches/peers/mujoco/` (`bench --peer` without a command).
pub const DEFAULT_PEER: &str = "python3 benches/peers/mujoco/peer.py";

#[derive(Parser)]
#[command(
    name = "tensegrity",
    version,
    about = "Check published tensegrity mechanism models against rigid-body dynamics"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand)]
pub enum Command {
    /// Run scenario files headless and compare the simulation with the analytic model.
    Run {
        /// Scenario files (`-`: one from standard input).
        #[arg(required = true)]
        scenarios: Vec<PathBuf>,
        /// Write the JSON report {"scenarios": [...]} to this file (`-`: standard output, the
        /// table then going to standard error).
        #[arg(long)]
        json: Option<PathBuf>,
        /// Record to this .rrd file (with several scenarios: one file each, STEM.rrd becoming
        /// STEM-<scenario>.rrd).
        #[arg(long)]
        record: Option<PathBuf>,
        /// Stream live to a running rerun viewer or server instead (default: rerun's own address,
        /// rerun+http://127.0.0.1:9876/proxy).
        #[arg(long, num_args = 0..=1, default_missing_value = "", value_name = "ADDR")]
        connect: Option<String>,
        /// Record every N-th tick only (thins long runs).
        #[arg(long, default_value_t = 1, value_name = "N", value_parser = clap::value_parser!(u64).range(1..))]
        record_every: u64,
        /// Write every tick as a row of this table at full f64 precision: CSV, or Arrow IPC for a
        /// name ending in .arrow, .feather or .ipc (with several scenarios: one file each,
        /// STEM-<scenario>.EXT, in the format its ending says).
        #[arg(long, value_name = "FILE.csv|FILE.arrow")]
        table: Option<PathBuf>,
        #[command(flatten)]
        set: SetArgs,
        /// Exit 1 when a scenario fails a check even where it declares that failure in
        /// `[expect]` (the exit code before: the physics' verdict instead of the declared one).
        #[arg(long)]
        fail_on_declared: bool,
        /// At each settle point, a proof of the equilibrium there (as `tensegrity certify`):
        /// the point report's `certificate` and a line under the point. Refused (exit 2) for a
        /// motion and a structure outside the proof's domain.
        #[arg(long)]
        certify: bool,
    },
    /// The equilibrium matrix A of a pin-jointed structure (point masses and strut bodies, no
    /// joints) at its settled state (its first point, settled as `run` settles it), and its
    /// SVD: rank r, s = b - r self-stress states (each member's tension), m = 3 j - r
    /// mechanisms (the nodes each moves most), Maxwell-Calladine's 3 j - b = m - s.
    Equilibrium {
        scenario: PathBuf,
        /// Write the JSON report to this file (`-`: standard output, the table then going to
        /// standard error).
        #[arg(long)]
        json: Option<PathBuf>,
        #[command(flatten)]
        set: SetArgs,
    },
    /// Natural frequencies and mode shapes of a scenario's structure at its settled state (its
    /// first point, settled as `run` settles it): free bodies held by springs and elastic
    /// cables (and by supports in some directions), or the revolute and prismatic joints of
    /// joint trees; joints that close loops, ball and universal joints, and taut inextensible
    /// cables are constraints; refused (exit 2): a loop closed by a prismatic joint. A mode that
    /// only the prestress stiffens is marked a mechanism. The constrained modes are reduced to the constraints' tangent space, the
    /// constraint forces' geometric stiffness included; slack cables are left out, and a
    /// structure the constraints hold rigid has no mode. Every mode, or above 100 free bodies
    /// on springs and elastic cables: the lowest 20 non-rigid modes and every rigid one
    /// (sparse shift-invert), the table saying of how many.
    Modes {
        scenario: PathBuf,
        /// Write the JSON report to this file (`-`: standard output, the table then going to
        /// standard error).
        #[arg(long)]
        json: Option<PathBuf>,
        /// Record each non-rigid mode animated at its frequency to this .rrd file (rerun).
        #[arg(long, value_name = "FILE.rrd")]
        record: Option<PathBuf>,
        /// Above 100 free bodies on springs and elastic cables: how many of the lowest
        /// non-rigid modes the sparse solver computes (1 to 200; every mode below).
        #[arg(long, default_value_t = crate::structure::SPARSE_MODAL_COUNT, value_name = "N",
              value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(1..=crate::structure::MAX_SPARSE_MODAL_COUNT as u64))]
        count: usize,
        #[command(flatten)]
        set: SetArgs,
    },
    /// How a scenario's settled state (its first point or `--point N`, settled as `run` settles it) moves
    /// with every parameter: d/dp of the node positions, joint coordinates, member forces, the
    /// mechanism's and the file's quantities and the lowest six natural frequencies, by the
    /// implicit function theorem (one linear solve per parameter on the tangent stiffness,
    /// dQ/dp by rebuilding the structure at p +- h and p +- 2 h with the state held). Free
    /// bodies held by springs and elastic cables, or joint trees; joints that close loops and
    /// taut inextensible cables are constraints, the derivatives taken in their tangent space
    /// with the move that keeps them (slack cables left out); refused (exit 2): cables with
    /// friction and a loop closed by a prismatic joint.
    Sensitivity {
        scenario: PathBuf,
        /// Write the JSON report to this file (`-`: standard output, the table then going to
        /// standard error).
        #[arg(long)]
        json: Option<PathBuf>,
        /// Write one row per parameter and output to this CSV file (`-`: standard output).
        #[arg(long, value_name = "FILE.csv")]
        csv: Option<PathBuf>,
        /// The settle point to analyse, from 0 as `run` numbers them (each settled afresh at
        /// its inputs and parameters).
        #[arg(long, default_value_t = 0, value_name = "N")]
        point: usize,
        /// Also measure every derivative by differences of settles (four settles per
        /// parameter) and report the largest error.
        #[arg(long)]
        check: bool,
        /// The parameter to differentiate by (repeatable; default: every parameter but the
        /// derived ones, which the report lists apart).
        #[arg(long = "param", value_name = "NAME")]
        params: Vec<String>,
        #[command(flatten)]
        set: SetArgs,
    },
    /// A proof, in interval arithmetic, that the settled state (its first point or `--point N`,
    /// settled as `run` settles it) is within a box holding exactly one equilibrium
    /// (Krawczyk's test on the equilibrium equations as built), with the largest box found,
    /// how far the settled state is from that equilibrium, and its stability proven over the
    /// box (the inertia of the stiffness; a lower bound on its smallest eigenvalue). Free
    /// bodies on springs and elastic cables, gravity and constant loads; refused (exit 2):
    /// joints, supports, inextensible and clustered cables, and a motion. Exit 0 when proven,
    /// 1 when not (the reason printed).
    Certify {
        scenario: PathBuf,
        /// Write the JSON report to this file (`-`: standard output, the table then going to
        /// standard error).
        #[arg(long)]
        json: Option<PathBuf>,
        /// The settle point to certify, from 0 as `run` numbers them.
        #[arg(long, default_value_t = 0, value_name = "N")]
        point: usize,
        #[command(flatten)]
        set: SetArgs,
    },
    /// What each idealization costs the file's model: its checks run under the ideal structure,
    /// under each `[[fidelity]]` relaxation alone (elastic struts, elastic or heavy cables, each
    /// with its data) and under all of them together; for every checked value at every point,
    /// every file model check and every measured frequency, the deviation from the model at each
    /// level, each relaxation's share of the change, and the interaction (what is left over).
    Attribute {
        scenario: PathBuf,
        /// Write the JSON report to this file (`-`: standard output, the table then going to
        /// standard error).
        #[arg(long)]
        json: Option<PathBuf>,
        /// Write one row per compared value (a grid's shares per point) to this CSV file (`-`:
        /// standard output).
        #[arg(long, value_name = "FILE.csv")]
        csv: Option<PathBuf>,
        /// Draw one bar per compared value, split by relaxation (FILE.svg or FILE.png).
        #[arg(long, value_name = "FILE.svg")]
        figure: Option<PathBuf>,
        #[command(flatten)]
        set: SetArgs,
    },
    /// Fit named parameters of a scenario to measured outputs (a CSV with the columns
    /// point,output,value[,sigma], and optionally t_s) by Levenberg-Marquardt, the Jacobian from
    /// the sensitivities at each measured point settled afresh, or for a row with a time t_s (a
    /// value of the scenario's motion then) from runs at each parameter's steps: the
    /// estimates, their covariance and 95 % intervals, the residual of each measurement, chi^2,
    /// and the parameter combinations the data cannot identify (their intervals infinite).
    Fit {
        scenario: PathBuf,
        /// The measurements: CSV with a header naming point, output, value and optionally
        /// sigma (the output's standard deviation, in its unit; without it the covariance is
        /// scaled by the reduced chi^2) and t_s (seconds since the motion's start: the row's
        /// output is then a column of the motion's per-tick table, as `run --table` names it).
        #[arg(long, value_name = "FILE.csv")]
        data: PathBuf,
        /// A parameter to fit, with optional bounds (repeatable): NAME, NAME=LOW:HIGH,
        /// NAME=LOW: or NAME=:HIGH.
        #[arg(long = "param", value_name = "NAME[=LOW:HIGH]", required = true)]
        params: Vec<String>,
        /// Write the JSON report to this file (`-`: standard output, the table then going to
        /// standard error).
        #[arg(long)]
        json: Option<PathBuf>,
        #[command(flatten)]
        set: SetArgs,
    },
    /// Validate scenario files without running them.
    Check {
        #[arg(required = true)]
        scenarios: Vec<PathBuf>,
        #[command(flatten)]
        set: SetArgs,
    },
    /// List the mechanisms: their parameters (units, defaults), inputs, start keys, checkable
    /// quantities and queries; with a scenario file, that file's mechanism (a custom file's own
    /// parameters), the parameter values the file gives and the symbols its model's expressions
    /// may use.
    List {
        scenario: Option<PathBuf>,
        #[command(flatten)]
        set: SetArgs,
    },
    /// Settle every point of a scenario's grid in parallel; write a CSV and a JSON summary.
    Sweep {
        scenario: PathBuf,
        /// The CSV (one row per point); default: print the summary only.
        #[arg(long)]
        out: Option<PathBuf>,
        /// The JSON summary.
        #[arg(long)]
        json: Option<PathBuf>,
        /// Worker threads (at most the machine's threads; more is lowered, and said).
        #[arg(long, default_value_t = 2, value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(1..))]
        jobs: usize,
        /// Run the K-th of N interleaved slices of the grid (for job arrays), as K/N.
        #[arg(long)]
        shard: Option<String>,
        /// A figure of the sweep (FILE.png or FILE.svg): each compared quantity, analytic and
        /// settled, against one axis, and the errors.
        #[arg(long)]
        figure: Option<PathBuf>,
        /// The figure's axis: an input or a swept parameter (default: the one with most values).
        #[arg(long)]
        x: Option<String>,
        /// At each point, a proof of the equilibrium there (as `tensegrity certify`): the CSV's
        /// `certified_*` columns. Refused (exit 2) for a motion and a structure outside the
        /// proof's domain.
        #[arg(long)]
        certify: bool,
        #[command(flatten)]
        set: SetArgs,
    },
    /// Draw one of the papers' figures (analytic, with the dynamics' verdict) as PNG and SVG.
    Figure {
        /// The figure's name (`tensegrity figure --list`).
        name: Option<String>,
        /// Directory for NAME.png and NAME.svg.
        #[arg(long, default_value = "assets/figures")]
        out: PathBuf,
        /// List the figures.
        #[arg(long)]
        list: bool,
    },
    /// Join the CSVs of a sharded sweep into one, rows in grid order.
    Merge {
        #[arg(required = true)]
        csvs: Vec<PathBuf>,
        /// The merged CSV (`-`: standard output).
        #[arg(long)]
        out: PathBuf,
        /// Merge what is there even when points of the grid are missing (a shard left out).
        #[arg(long)]
        partial: bool,
    },
    /// The analytic model alone: print every result of a query.
    Solve {
        mechanism: String,
        query: String,
        /// NAME=VALUE for a parameter or an input (repeatable).
        #[arg(long = "set", value_name = "NAME=VALUE")]
        set: Vec<String>,
        /// Print JSON instead of a table.
        #[arg(long)]
        json: bool,
    },
    /// Measure settling speed and accuracy on the built-in case sets (medians over rounds).
    Bench {
        /// Rounds per case set.
        #[arg(long, default_value_t = 5)]
        rounds: usize,
        /// Print JSON instead of a table.
        #[arg(long)]
        json: bool,
        /// Write each case set as DIR/MECHANISM.json for a peer simulator (parameters, time
        /// step, settle criterion, inputs, analytic values, start and analytic node positions)
        /// and stop.
        #[arg(long, value_name = "DIR")]
        export_cases: Option<PathBuf>,
        /// Only this mechanism's case set (repeatable; default: all).
        #[arg(long = "mechanism", value_name = "NAME")]
        mechanisms: Vec<String>,
        /// Also run each case set through a peer simulator, alternating rounds with the
        /// testbed, and print the ratios. CMD gets the case-set file, `--rounds 1` and
        /// `--min-round-wall-s S` (the testbed's shortest round) appended (default: the MuJoCo
        /// peer, `benches/peers/mujoco/peer.py` run by `$TENSEGRITY_PYTHON`, else python3).
        #[arg(long, value_name = "CMD", num_args = 0..=1, default_missing_value = DEFAULT_PEER)]
        peer: Option<String>,
        /// Settle the scale families instead (n-strut prisms, the icosahedron, force-density
        /// towers, furet2018 X chains, tensegrity spines) from perturbed starts: steps, wall
        /// time, memory, error against the closed form, growth exponent. With --peer: the same
        /// structures in MuJoCo too (default `benches/peers/mujoco/scale_peer.py`).
        #[arg(long)]
        scale: bool,
        /// With --scale: largest structure, in struts.
        #[arg(long, value_name = "N", default_value_t = 1000)]
        max_struts: usize,
        /// With --scale: only this family (prism, icosahedron, tower, furet, spine; with --motion
        /// also pendulum, rocker, spin, cart, and not furet; repeatable).
        #[arg(long = "family", value_name = "NAME")]
        families: Vec<String>,
        /// With --scale: a case still moving after this wall time is reported as not settled
        /// (checked between steps) [s].
        #[arg(long, value_name = "S", default_value_t = 120.0)]
        max_case_wall_s: f64,
        /// With --scale --peer: physical motion instead of settling. The free-body families
        /// and the pendulum, rocker, spin and driven cart move undamped from their starts at
        /// several time steps on both sides, scored against MuJoCo's RK4; steps per second, the cost at
        /// equal error, and the judged motion (extrapolated over the step) against MuJoCo's RK4
        /// and Euler at equal stepping time.
        #[arg(long, requires = "scale")]
        motion: bool,
    },
    /// Write a scenario's structure in another simulator's format.
    Export {
        #[command(subcommand)]
        format: ExportFormat,
    },
    /// Read a structure from another tool's format and write it as a scenario file.
    Import {
        #[command(subcommand)]
        format: ImportFormat,
    },
    /// Check every printed equation of a mechanism's paper against the testbed's derivation.
    Findings {
        mechanism: String,
        /// NAME=VALUE for a parameter (repeatable).
        #[arg(long = "set", value_name = "NAME=VALUE")]
        set: Vec<String>,
        /// Print JSON instead of a list.
        #[arg(long)]
        json: bool,
    },
}

#[derive(Subcommand)]
pub enum ExportFormat {
    /// MuJoCo MJCF XML of the structure at the scenario's first actuation point.
    Mjcf {
        scenario: PathBuf,
        /// The XML file (default: stdout).
        #[arg(long)]
        out: Option<PathBuf>,
        /// How the testbed's ideal actuators are written: `mocap` (bodies placed by actuated
        /// joints are mocap bodies: exact) or `position` (position servos of gain --kp).
        #[arg(long, default_value = "mocap", value_parser = ["mocap", "position"])]
        actuators: String,
        /// Gain of the position actuators on joints [N/m or N m/rad].
        #[arg(long, default_value_t = 1e6)]
        kp: f64,
        /// Viscous damping along every cable [N s/m] (tendon damping, winch kv): zero at rest,
        /// it only helps MuJoCo settle (the testbed's cables have none).
        #[arg(long, default_value_t = 0.0)]
        cable_damping: f64,
        #[command(flatten)]
        set: SetArgs,
    },
}

#[derive(Subcommand)]
pub enum ImportFormat {
    /// An NTRT YAML model (nodes, pair_groups, builders, substructures, bond_groups).
    Ntrt {
        file: PathBuf,
        /// The scenario file (default: stdout).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Keep NTRT's axes (y up) instead of mapping its y to the testbed's z.
        #[arg(long)]
        keep_axes: bool,
    },
    /// A node matrix N (3 x n) and connectivity matrices C_b (bars x n) and C_s (strings x n),
    /// as CSV (Skelton and de Oliveira's notation, TsgFEM, MOTES).
    Matrices {
        n: PathBuf,
        cb: PathBuf,
        cs: PathBuf,
        /// The scenario file (default: stdout).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Mass of each bar [kg].
        #[arg(long, default_value_t = MatrixOptions::DEFAULT.bar_mass_kg)]
        bar_mass: f64,
        /// Radius of each bar [m].
        #[arg(long, default_value_t = MatrixOptions::DEFAULT.bar_radius_m)]
        bar_radius: f64,
        /// Stiffness of each string [N/m].
        #[arg(long, default_value_t = MatrixOptions::DEFAULT.string_stiffness_n_per_m)]
        string_stiffness: f64,
        /// The least string tension at the drawn state [N]: the drawn structure's self-stress
        /// scaled to it sets each string's rest length (every string at it with
        /// --uniform-tension, or when the drawing has no self-stress with every string taut).
        #[arg(long, default_value_t = MatrixOptions::DEFAULT.string_tension_n)]
        string_tension: f64,
        /// Every string at --string-tension, whatever the drawn structure's self-stress.
        #[arg(long)]
        uniform_tension: bool,
        /// A clustering matrix S as CSV (CTSFEM's): one row per clustered cable, one column
        /// per string, 1 where the string is a segment of it; each row's strings become one
        /// cable through their nodes (one tension, sliding at the inner nodes).
        #[arg(long, value_name = "S.csv")]
        clusters: Option<PathBuf>,
    },
}

/// `--set NAME=VALUE` on a command that reads a scenario.
#[derive(clap::Args)]
pub struct SetArgs {
    /// Override a parameter (NAME=VALUE, a number or an expression) or a setting
    /// (sim.KEY=VALUE, settle.KEY=VALUE) of the scenario (repeatable).
    #[arg(long = "set", value_name = "NAME=VALUE")]
    pub set: Vec<String>,
}
