//! The view search counted in parts (issue #44) against the one-process search, on `body`
//! phantoms (i16, as the CLI's): (a) `search` of the whole volume; (b) the same counts as the
//! Dask tasks make them: for each slab of N cell planes along z, the slab's volume built as
//! `_count_view_slab` builds it (`Volume::of_slab` of the grid), its rounds made from it,
//! `ViewRounds::count_slab`, each part sent as bytes and added on the "client" as `total +=
//! part` adds (in place), then `finish`; (c) the phases of (b): CPU
//! seconds (the process's user + system, every thread's) and wall seconds of each, and the parts'
//! size (bytes as sent, open pieces of rays a lattice). Checks that (b)'s result is (a)'s, as
//! JSON. Prints the medians of `--runs` runs, taken in turns.
//!
//! `cargo bench --bench slab_bench -- [--sizes 256x256x256,512x512x512] [--slabs 64,32]
//! [--params paper|defaults] [--runs 3]`

use std::ops::Range;
use std::time::Instant;

use slabscope::Volume;
use slabscope::measure::PartialCounts;
use slabscope::progress::Monitor;
use slabscope::view::{ViewParams, ViewRound, ViewRounds, search};
use slabscope::volume::{SlabGrid, Voxels, phantom};

mod common;
use common::{arg, median, parse_dims};

/// The process's CPU seconds so far, every thread's, user and system.
fn cpu() -> f64 {
    let mut usage = std::mem::MaybeUninit::<libc::rusage>::zeroed();
    // SAFETY: getrusage writes a whole rusage into the pointer given, which points to one.
    #[allow(unsafe_code)]
    let usage = unsafe {
        libc::getrusage(libc::RUSAGE_SELF, usage.as_mut_ptr());
        usage.assume_init()
    };
    let secs = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
    secs(usage.ru_utime) + secs(usage.ru_stime)
}

/// CPU and wall seconds of phases, added up.
#[derive(Default, Clone, Copy)]
struct Spent {
    cpu: f64,
    wall: f64,
}

impl Spent {
    fn time<R>(&mut self, f: impl FnOnce() -> R) -> R {
        let (c, w) = (cpu(), Instant::now());
        let out = f();
        self.cpu += cpu() - c;
        self.wall += w.elapsed().as_secs_f64();
        out
    }
}

/// One run of (b): the phases' times, the bytes sent, the open pieces a lattice (the largest
/// part's), and the result as JSON.
struct Split {
    of_slab: Spent,
    rounds: Spent,
    count: Spent,
    send: Spent,
    add: Spent,
    finish: Spent,
    bytes: usize,
    pieces: usize,
    json: String,
}

/// The voxel planes of `held` of `v` as the slab's volume a task builds.
fn slab_volume(v: &Volume, held: &Range<usize>) -> Volume {
    let [nx, ny, _] = v.dims();
    let grid = SlabGrid::of(v);
    let planes = held.start * nx * ny..held.end * nx * ny;
    match v.data() {
        Voxels::U8(s) => Volume::of_slab(&grid, held.start, &s.as_slice()[planes]),
        Voxels::I8(s) => Volume::of_slab(&grid, held.start, &s.as_slice()[planes]),
        Voxels::U16(s) => Volume::of_slab(&grid, held.start, &s.as_slice()[planes]),
        Voxels::I16(s) => Volume::of_slab(&grid, held.start, &s.as_slice()[planes]),
        Voxels::F32(s) => Volume::of_slab(&grid, held.start, &s.as_slice()[planes]),
    }
    .expect("a slab of the grid")
}

/// A round's parts of `slabs`, as tasks count them, added as the client adds them.
fn round(
    v: &Volume,
    params: &ViewParams,
    round: &ViewRound,
    slabs: &[Range<usize>],
    split: &mut Split,
) -> Vec<PartialCounts> {
    let nz = v.dims()[2];
    let whole = ViewRounds::new(v, params).expect("rounds");
    let mut total: Option<Vec<PartialCounts>> = None;
    for planes in slabs {
        let held = whole.voxel_planes(planes, nz);
        let slab = split.of_slab.time(|| slab_volume(v, &held));
        let rounds = split
            .rounds
            .time(|| ViewRounds::new(&slab, params).expect("rounds"));
        let part = split.count.time(|| {
            rounds
                .count_slab(&slab, round, planes.clone())
                .expect("counts")
        });
        split.pieces = split
            .pieces
            .max(part.iter().map(|p| p.fragments().len()).max().unwrap_or(0));
        drop(slab);
        let part: Vec<PartialCounts> = split.send.time(|| {
            part.iter()
                .map(|p| {
                    let bytes = p.to_bytes();
                    split.bytes += bytes.len();
                    PartialCounts::from_bytes(&bytes).expect("bytes read back")
                })
                .collect()
        });
        // `total += part`, as the client adds: the part added in place, the total not copied.
        split.add.time(|| match &mut total {
            None => total = Some(part),
            Some(t) => {
                for (s, p) in t.iter_mut().zip(&part) {
                    s.add_ref(p);
                }
            }
        });
    }
    total.expect("a slab at least")
}

fn split(v: &Volume, params: &ViewParams, depth: usize) -> Split {
    let cells = v.dims()[2] - 1;
    let slabs: Vec<Range<usize>> = (0..cells)
        .step_by(depth)
        .map(|s| s..(s + depth).min(cells))
        .collect();
    let mut out = Split {
        of_slab: Spent::default(),
        rounds: Spent::default(),
        count: Spent::default(),
        send: Spent::default(),
        add: Spent::default(),
        finish: Spent::default(),
        bytes: 0,
        pieces: 0,
        json: String::new(),
    };
    let rounds = ViewRounds::new(v, params).expect("rounds");
    let paper = round(v, params, &ViewRound::Paper, &slabs, &mut out);
    // The shifted lattices the paper round did not count (none on a volume of 232³ or more).
    let next = rounds.shifted_after(v, &ViewRound::Paper, &paper);
    let shifted = match next.expect("samples") {
        Some(next) => round(v, params, &next, &slabs, &mut out),
        None => Vec::new(),
    };
    let result = out
        .finish
        .time(|| rounds.finish(v, &paper, &shifted).expect("finish"));
    out.json = serde_json::to_string(&result).expect("json");
    out
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let sizes = arg("--sizes").unwrap_or_else(|| "256x256x256".into());
    let depths: Vec<usize> = arg("--slabs")
        .unwrap_or_else(|| "64,32".into())
        .split(',')
        .map(str::parse)
        .collect::<Result<_, _>>()?;
    let runs: usize = arg("--runs").map_or(Ok(3), |r| r.parse())?;
    let params = match arg("--params").as_deref() {
        Some("defaults") => ViewParams::default(),
        _ => ViewParams::paper(),
    };
    for dims in sizes.split(',').map(parse_dims) {
        let dims = dims.ok_or("--sizes: NXxNYxNZ,...")?;
        let v = phantom::body(dims, 1)?;
        let mut one = (Vec::new(), Vec::new());
        let mut parts: Vec<Vec<Split>> = depths.iter().map(|_| Vec::new()).collect();
        for _ in 0..runs {
            let mut spent = Spent::default();
            let expect = spent.time(|| search(&v, &params, &Monitor::none()))?;
            let expect = serde_json::to_string(&expect)?;
            one.0.push(spent.cpu);
            one.1.push(spent.wall);
            for (d, &depth) in depths.iter().enumerate() {
                let s = split(&v, &params, depth);
                assert_eq!(
                    s.json, expect,
                    "{dims:?} in slabs of {depth}: not the search"
                );
                parts[d].push(s);
            }
        }
        println!(
            "{}x{}x{}: one process {:.2} s CPU, {:.2} s wall",
            dims[0],
            dims[1],
            dims[2],
            median(one.0),
            median(one.1)
        );
        for (depth, runs) in depths.iter().zip(&parts) {
            let med = |f: &dyn Fn(&Split) -> Spent| {
                let cpu = median(runs.iter().map(|s| f(s).cpu).collect());
                let wall = median(runs.iter().map(|s| f(s).wall).collect());
                format!("{cpu:.3}/{wall:.3}")
            };
            println!(
                "  slabs of {depth} (parts equal the search): CPU/wall s: of_slab {}, rounds {}, \
                 count_slab {}, bytes {}, add {}, finish {}; {} bytes sent, at most {} open \
                 pieces a lattice",
                med(&|s| s.of_slab),
                med(&|s| s.rounds),
                med(&|s| s.count),
                med(&|s| s.send),
                med(&|s| s.add),
                med(&|s| s.finish),
                runs[0].bytes,
                runs[0].pieces,
            );
        }
    }
    Ok(())
}
