//! The command line of `coordinator bound`.

use std::path::PathBuf;

use clap::Args;

/// Arguments of `bound`.
#[derive(Debug, Args)]
#[command(group(clap::ArgGroup::new("searches").args(["alone", "together"]).multiple(true)))]
pub struct BoundArgs {
    /// The scenario file (TOML); the embedded paper example when omitted.
    pub scenario: Option<PathBuf>,
    /// Also run each agent alone: the method with no mate, and the best track a search
    /// over a lattice finds (an achievable track: the least deviation alone lies between
    /// the bound and it). Slower: a simulation and a search per agent.
    #[arg(long)]
    pub alone: bool,
    /// Also search the formation's tracks together: each agent's best track on the
    /// lattice in turn, kept clear of the tracks before it, in a few orders (an
    /// achievable formation, mates included: the least deviation lies between the bound
    /// and it). Slower: a search per agent and order.
    #[arg(long)]
    pub together: bool,
    /// With `--together`: write the tracks found together to this CSV file (`step`,
    /// `agent`, `x_m`, `y_m`: each agent's position at every step, step 0 its slot; the
    /// agents move in the order the report names), to plot or replay them.
    #[arg(long, value_name = "FILE", requires = "together")]
    pub together_csv: Option<PathBuf>,
    /// Lattice points per top-speed move of the searches of `--alone` and `--together`
    /// (5 unless given): a finer lattice finds tracks nearer the least achievable
    /// deviation, in more time (about (N/5)² times the default's).
    #[arg(long, value_name = "N", requires = "searches",
          value_parser = clap::value_parser!(u32).range(2..=20))]
    pub lattice_per_move: Option<u32>,
}
