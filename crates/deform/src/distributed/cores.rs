//! Rank 0's threads for its serial part of a partition made there: reading the grid, the
//! cut, the parts and their encoding, and the gathered write. The other ranks of its node
//! wait for it asleep ([`wait_idle`], `broadcast_idle`), so their cores are free; a thread
//! pool on rank 0 ([`root_pool`]) takes them.
//!
//! Open MPI binds each rank to one core by default (`--bind-to core` for two ranks or
//! more), and threads inherit their process's binding: rank 0's own rayon pool would run
//! all its threads on its one core. The pool's threads are bound to the union of the cores
//! of the ranks on rank 0's node instead (`sched_setaffinity`, through the `nix` crate: the
//! workspace forbids `unsafe`, and `nix` is the well-kept safe binding of it). At 1M nodes
//! on 2 ranks, the partition took 4.6–5.0 s on one core and 3.6–4.3 s on the pool's two
//! (four runs each; docs/perf-log/2026-12-04-mpi-root-pool.md).

use mpi::traits::*;

use super::comm::Comm;

/// The words of a CPU mask (1024 CPUs, as glibc's `cpu_set_t`).
const WORDS: usize = 16;

/// The CPUs this process may run on, as bits (CPU `c` is bit `c % 64` of word `c / 64`);
/// `None` when the mask cannot be read.
#[cfg(target_os = "linux")]
fn own_cpus() -> Option<[u64; WORDS]> {
    use nix::sched::{CpuSet, sched_getaffinity};
    use nix::unistd::Pid;
    let set = sched_getaffinity(Pid::from_raw(0)).ok()?;
    let mut words = [0u64; WORDS];
    for c in 0..CpuSet::count().min(64 * WORDS) {
        if set.is_set(c).unwrap_or(false) {
            words[c / 64] |= 1 << (c % 64);
        }
    }
    Some(words)
}

#[cfg(not(target_os = "linux"))]
fn own_cpus() -> Option<[u64; WORDS]> {
    None
}

/// Binds the calling thread to the CPUs of `words` (best effort: a refusal leaves it where
/// it was).
#[cfg(target_os = "linux")]
fn bind(words: &[u64; WORDS]) {
    use nix::sched::{CpuSet, sched_setaffinity};
    use nix::unistd::Pid;
    let mut set = CpuSet::new();
    for c in 0..CpuSet::count().min(64 * WORDS) {
        if words[c / 64] >> (c % 64) & 1 == 1 {
            let _ = set.set(c);
        }
    }
    let _ = sched_setaffinity(Pid::from_raw(0), &set);
}

#[cfg(not(target_os = "linux"))]
fn bind(_: &[u64; WORDS]) {}

/// A thread pool for rank 0 on the cores of the ranks of its node (`None` on the other
/// ranks, and on rank 0 when it would have one thread or the masks cannot be read):
/// min(node's ranks × this process's rayon threads, the CPUs of their masks) threads, each
/// bound to those CPUs. Collective over `comm`.
pub fn root_pool(comm: &Comm) -> Option<rayon::ThreadPool> {
    let node = comm.split_shared(comm.rank());
    // Each rank's mask (all zero when unreadable: it adds no CPU).
    let mine = own_cpus();
    let mut all = vec![0u64; WORDS * node.size() as usize];
    node.all_gather_into(&mine.unwrap_or([0; WORDS])[..], &mut all[..]);
    if comm.rank() != 0 {
        return None;
    }
    mine?;
    let mut union = [0u64; WORDS];
    for r in all.chunks_exact(WORDS) {
        for (u, w) in union.iter_mut().zip(r) {
            *u |= w;
        }
    }
    let cpus: usize = union.iter().map(|w| w.count_ones() as usize).sum();
    let threads = (node.size() as usize * rayon::current_num_threads()).min(cpus);
    if threads < 2 {
        return None;
    }
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .thread_name(|k| format!("aeroshape-root-{k}"))
        .start_handler(move |_| bind(&union))
        .build()
        .ok()
}

/// Runs `f` in `pool` when there is one, on the calling thread's pool otherwise.
pub(crate) fn on_pool<T: Send>(
    pool: Option<&rayon::ThreadPool>,
    f: impl FnOnce() -> T + Send,
) -> T {
    match pool {
        Some(p) => p.install(f),
        None => f(),
    }
}

/// `f` run on rank 0 on its pool over the cores of the ranks of its node ([`root_pool`]),
/// the other ranks waiting for it asleep ([`wait_idle`]); `None` on the other ranks.
/// Collective: how a caller reads or writes the whole grid on rank 0 (`mpirun aeroshape
/// deform`: at 1M nodes on 2 ranks the read took 0.47–0.56 s so against 0.65–0.94 s on rank
/// 0's one core, the write 0.51–0.66 s against 0.69–0.84 s).
pub fn on_root<T: Send>(comm: &Comm, f: impl FnOnce() -> T + Send) -> Option<T> {
    let pool = root_pool(comm);
    let out = (comm.rank() == 0).then(|| on_pool(pool.as_ref(), f));
    drop(pool);
    wait_idle(comm);
    out
}

/// Tests `req` every 2 ms until it completes, asleep in between (a blocking wait polls:
/// while rank 0 works alone, for seconds, the waiting ranks would take the CPU time its
/// pool needs).
fn complete_asleep<'a, D: ?Sized, S: mpi::request::Scope<'a>>(
    mut req: mpi::request::Request<'a, D, S>,
) {
    while let Err(r) = req.test() {
        req = r;
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
}

/// Waits for every rank of `comm` without keeping a core busy. Collective.
pub fn wait_idle(comm: &Comm) {
    complete_asleep(comm.immediate_barrier());
}

/// Broadcasts `v` from rank 0, the other ranks waiting for it as [`wait_idle`] does.
/// Collective.
pub(crate) fn broadcast_idle(comm: &Comm, v: &mut u64) {
    let root = comm.process_at_rank(0);
    mpi::request::scope(|sc| complete_asleep(root.immediate_broadcast_into(sc, v)));
}
