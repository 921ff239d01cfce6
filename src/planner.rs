//! `peritherm partition`: what each of N ranks would hold and exchange in a distributed run of
//! a case, and the time per step a latency–bandwidth model gives, without running it (nor
//! building its bonds): the cloud, the partition every rank would compute
//! ([`Partition::by_estimate`]) and a counting neighbour search per rank
//! ([`peritherm_core::partition::loads`]).

use crate::budget::share_bytes;
use crate::case::Case;
use crate::error::Result;
use crate::model::Model;
use crate::partition::{loads, rule_sources, Partition, RankLoad};
use crate::prepare::keyed;

/// Bytes a Euler step streams per pair of K: a u32 column and an f64 K_ij
/// ([`crate::bench::BYTES_PER_BOND`]), B.
const STREAM_BYTES_PER_PAIR: f64 = crate::bench::BYTES_PER_BOND;

/// Bytes a Euler step streams per row besides its pairs: θ_i read, θ_i written, 1/(V_i ρc_i)
/// read, B.
const STREAM_BYTES_PER_ROW: f64 = 24.0;

/// The machine a plan is for: the parameters of the latency–bandwidth model.
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct Machine {
    /// Memory bandwidth of one rank (its share of a node's), GB/s.
    pub bandwidth: f64,
    /// Latency of one message between ranks, µs.
    pub latency: f64,
    /// Bandwidth of the link between ranks, GB/s.
    pub link: f64,
}

/// What the ranks of one rank count hold, at most or at least over the ranks, and the model's
/// time per step.
#[derive(Debug, Clone, serde::Serialize)]
pub struct PlanRow {
    /// Number of ranks.
    pub ranks: usize,
    /// The fewest and most body nodes of a rank.
    pub nodes: (usize, usize),
    /// The most ghost nodes a rank receives per exchange.
    pub ghosts: usize,
    /// The most ranks one rank receives from.
    pub neighbours: usize,
    /// The most directed bonds of a rank.
    pub bonds: usize,
    /// The most memory of a rank ([`share_bytes`]), B.
    pub memory: f64,
    /// The most bytes a rank receives per halo exchange, B.
    pub halo_bytes: usize,
    /// The slowest rank's stream of its rows per step, s.
    pub compute: f64,
    /// The slowest rank's halo exchange per step, s.
    pub exchange: f64,
    /// The slowest rank's step, s.
    pub step: f64,
}

/// The plan of `case` on each rank count of `ranks` for `machine` (halo exchanges per step:
/// one for Euler, four for RK4).
pub fn plan(case: &Case, ranks: &[usize], machine: &Machine) -> Result<Vec<PlanRow>> {
    let (cloud, boundary) = Model::outline(&case.spec).map_err(|e| keyed(case, e))?;
    let sources = rule_sources(cloud.len(), &boundary.linear_rules());
    let stages = match case.integrator {
        crate::solve::Integrator::Rk4 => 4.0,
        _ => 1.0,
    };
    let all_nodes = cloud.len();
    let rows = ranks.iter().map(|&n| {
        let partition = Partition::by_estimate(&cloud, n);
        let each = loads(&cloud, &case.spec.kernel, &sources, &partition);
        row(n, &each, all_nodes, stages, machine)
    });
    Ok(rows.collect())
}

/// The [`PlanRow`] of the loads of `n` ranks.
fn row(n: usize, each: &[RankLoad], all_nodes: usize, stages: f64, m: &Machine) -> PlanRow {
    let most = |f: &dyn Fn(&RankLoad) -> usize| each.iter().map(f).max().unwrap_or(0);
    let time = |l: &RankLoad| {
        let bytes = l.pairs as f64 * STREAM_BYTES_PER_PAIR + l.nodes as f64 * STREAM_BYTES_PER_ROW;
        let compute = stages * bytes / (m.bandwidth * 1e9);
        let exchange = match n {
            1 => 0.0,
            _ => {
                stages
                    * (2.0 * l.sources as f64 * m.latency * 1e-6
                        + 8.0 * l.ghosts as f64 / (m.link * 1e9))
            }
        };
        (compute, exchange)
    };
    let slowest = each
        .iter()
        .map(time)
        .max_by(|a, b| (a.0 + a.1).total_cmp(&(b.0 + b.1)))
        .unwrap_or((0.0, 0.0));
    PlanRow {
        ranks: n,
        nodes: (
            each.iter().map(|l| l.nodes).min().unwrap_or(0),
            most(&|l| l.nodes),
        ),
        ghosts: most(&|l| l.ghosts),
        neighbours: most(&|l| l.sources),
        bonds: most(&|l| l.bonds),
        memory: each
            .iter()
            .map(|l| share_bytes(l.nodes as f64, l.bonds as f64, all_nodes as f64))
            .fold(0.0, f64::max),
        halo_bytes: most(&|l| l.ghosts) * 8,
        compute: slowest.0,
        exchange: slowest.1,
        step: slowest.0 + slowest.1,
    }
}

/// The plan as a Markdown table, with the model's parameters and the speed-up over one rank
/// (the first row when it is for one rank).
pub fn markdown(case: &Case, rows: &[PlanRow], m: &Machine) -> String {
    let mut s = format!(
        "{}: {} ranks' shares (`peritherm partition`)\n\nModel: a step streams {STREAM_BYTES_PER_PAIR} B per pair of K and {STREAM_BYTES_PER_ROW} B per row at {} GB/s per rank; a halo exchange costs {} µs per neighbour rank (a send and a receive) plus 8 B per ghost at {} GB/s; the slowest rank sets the step. Memory per rank: the memory budget's bytes per node and per bond for its rows and bonds, plus {} B for every node of the cloud (held whole on every rank).\n\n",
        case.path.display(),
        rows.len(),
        m.bandwidth,
        m.latency,
        m.link,
        crate::limits::SHARED_BYTES_PER_NODE,
    );
    s += "| ranks | nodes per rank | ghosts (most) | neighbour ranks (most) | bonds (most) | memory per rank (most) | halo bytes per exchange (most) | step: stream + exchange | speed-up |\n";
    s += "|---|---|---|---|---|---|---|---|---|\n";
    let base = rows.first().filter(|r| r.ranks == 1).map(|r| r.step);
    for r in rows {
        let speedup = base.map_or("-".into(), |b| format!("{:.0}", b / r.step));
        s += &format!(
            "| {} | {}–{} | {} | {} | {:.3e} | {} | {} | {:.3e} s + {:.3e} s | {} |\n",
            r.ranks,
            r.nodes.0,
            r.nodes.1,
            r.ghosts,
            r.neighbours,
            r.bonds as f64,
            crate::budget::human(r.memory),
            r.halo_bytes,
            r.compute,
            r.exchange,
            speedup
        );
    }
    s
}

/// The plan as JSON (`partition.json` of `peritherm partition --out DIR`): the machine and
/// the rows; the same bytes whenever the same case and ranks are planned.
pub fn json(machine: &Machine, rows: &[PlanRow]) -> String {
    let v = serde_json::json!({ "machine": machine, "rows": rows });
    serde_json::to_string_pretty(&v).expect("plain data serialises")
}

/// The plan as a figure file named `name` (`peritherm partition --json FILE`), measured by
/// `command`, with its check: `args` (the arguments of `peritherm` that planned it) write
/// `partition.json` with the same bytes.
pub fn figures(
    name: &str,
    command: &str,
    table: &str,
    args: Vec<String>,
    json: &str,
) -> peritherm_post::figures::Figures {
    use peritherm_post::figures::{fnv1a_hex, from_markdown, Check};
    let provenance = crate::figures::provenance(rayon::current_num_threads());
    let mut f = from_markdown(name, command, provenance, table);
    f.checks.push(Check::File {
        args,
        file: "partition.json".into(),
        fnv1a: fnv1a_hex(json.as_bytes()),
    });
    f
}
