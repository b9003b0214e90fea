// The evaluation's training plan: which models the folds need, shared where folds can share them, and trained
// `jobs` at a time before any fold is scored.
//
// A fold trains its final G and, for the change gate (stargan/gate.hpp), one inner G per inner group of its
// training contents. With each fold dealing its own contents round the groups (per-fold groups), no two folds
// train the same inner model: 2 N inner trainings for N folds. The shared plan partitions every fold's training
// contents so that the inner models repeat across folds. The sorted contents c_0 .. c_{N-1} are cut into
// A = c_0 .. c_{a-1}, a = floor((N - 1) / 2), and C = the rest, with pivot p = the first of C:
//   - a fold holding out k in C has the groups A and C \ {k};
//   - a fold holding out k in A has the groups (A \ {k}) + {p} and C \ {p}.
// Each group is scored with the G trained on the fold's other group, so the inner models are G on A (shared by
// every fold in C), G on C \ {k} for each k in C (C \ {p} also serves every fold in A) and G on (A \ {k}) + {p}
// for each k in A: N + 1 trainings instead of 2 N (8 instead of 14 for 7 contents). The groups are as even as
// the per-fold ones (3 and 3 for 7 contents; for 12, 5 and 6) and fixed by the content names alone, before any
// clip is read. Inner model i (in the order above) is trained with seed train.seed + 7919 (i + 1) into
// <report>/inner/model<i + 1>/, whichever fold asks for it first; every other fold reuses it.
//
// The ring plan needs one model fewer for an odd number of contents. The contents sit on a ring, c_{N} = c_0,
// and the run R_s = c_s .. c_{s+a-1} (indices mod N) holds a = (N - 1) / 2 consecutive contents. The fold holding
// out c_k has the groups R_{k+1} and R_{k+a+1}, which together hold every content but c_k; each is scored with the
// G trained on the other. The inner models are the G on each run, N of them (7 for 7 contents, against 8 shared and
// 14 per fold), each shared by two folds (G on R_s scores for the folds holding out c_{s-1} and c_{s+a-1}); the
// groups are a and a contents, as even as the shared plan's. With N + 1 inner models and N final Gs, 2 trainings at
// a time leave one training alone at the end; with N they pair up exactly. For an even N the two groups of a fold
// differ in size, the runs of both sizes would be 2 N models, and the ring plan is the shared plan. Ring model s is
// trained with seed train.seed + 7919 (s + 1) into <report>/inner/ring<s + 1>/ (other folders than the shared
// plan's, so that --reuse-models never takes one plan's model for the other's).
//
// train_all() trains every inner model and every fold's final G first, `jobs` of them at once on their own
// threads, each with train.threads threads (1 when it is 0 and jobs > 1); a final G waits for its two inner
// models. Training is deterministic for a seed and thread count, so the models are bit for bit those of
// training them one after another (a test checks it), and the folds are then scored one by one with them.
//
// Across the processes of a group (eval_options::group, dist/group.hpp; `handemo eval --mpi`), run_training_waves()
// runs the same plan in waves: wave 1 is every job that waits on none (the inner models), wave 2 every job that
// waits only on wave 1 (the final Gs), and so on. Each wave's jobs, counted in plan order from 0, are dealt round
// the processes: job i of a wave runs on process i mod R (wave_rank()), so with every fold trained, fold k's final
// G runs on process k mod R. Each process runs its share of a wave `jobs` at a time, as run_training_jobs() does,
// and writes the models into the report folder, which every process must see (a shared file system, as on a
// cluster). At the end of a wave the processes gather every job's seconds (an all-gather, so also a barrier), and
// every process checks that every model of the wave is there before the next wave reads them. The jobs and seeds
// are those of one process, so the models are bit for bit those of one process with the same threads per training.
// Two dependent waves bound the gain: with N + 1 inner models and N final Gs, more than N + 1 processes (times
// `jobs`) leave some idle, and the evaluation takes at least two trainings' time plus the scoring on process 0.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/core/io.hpp>
#include <handemo/core/progress.hpp>
#include <handemo/dist/group.hpp>
#include <handemo/stargan/dataset.hpp>
#include <handemo/stargan/gate.hpp>
#include <handemo/stargan/train.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

namespace handemo::eval {

/// @brief How the change gate's inner groups are formed in an evaluation (eval_options::gate_groups).
enum class gate_groups {
    shared,    ///< the shared plan (schedule.hpp): N + 1 inner models for N folds
    per_fold,  ///< each fold's sorted training contents dealt round the groups (`handemo train`'s own): 2 N
    ring       ///< the ring plan (schedule.hpp): N inner models for an odd N, the shared plan's for an even N
};

/// @brief "shared", "per-fold" or "ring".
inline const char* to_string(gate_groups g) noexcept
{
    return g == gate_groups::shared ? "shared" : g == gate_groups::ring ? "ring" : "per-fold";
}

/// @brief Parses "shared", "per-fold" or "ring".
/// @throws value_error naming the value.
inline gate_groups parse_gate_groups(const std::string& s)
{
    if (s == "shared") return gate_groups::shared;
    if (s == "per-fold") return gate_groups::per_fold;
    if (s == "ring") return gate_groups::ring;
    throw value_error("eval: --gate-groups '" + s + "' is not 'shared', 'ring' or 'per-fold'");
}

/// @brief The shared plan's inner groups for the fold holding out `held` (see the header comment).
/// @param contents every content of the data set, sorted
/// @param inner_root where the shared inner models live (<report>/inner)
/// @param seed the evaluation's base seed (train.seed)
/// @return the plan, or nothing for fewer than 3 contents (no two inner groups to form)
/// @throws value_error when `held` is not one of `contents`.
inline std::optional<stargan::gate_plan> shared_gate_plan(const std::vector<std::string>& contents, const std::string& held,
                                                          const std::filesystem::path& inner_root, std::uint64_t seed)
{
    const auto at = std::find(contents.begin(), contents.end(), held);
    if (at == contents.end()) throw value_error("eval: shared gate plan: content '" + held + "' is not in the data set");
    const std::size_t N = contents.size();
    if (N < 3) return std::nullopt;
    const std::size_t a = (N - 1) / 2;  // |A| >= 1, |C| = N - a >= 2
    const std::size_t k = static_cast<std::size_t>(at - contents.begin());
    const std::size_t p = a;  // the pivot, the first of C
    auto range = [&](std::size_t from, std::size_t to, std::size_t skip) {
        std::vector<std::string> v;
        for (std::size_t i = from; i < to; ++i)
            if (i != skip) v.push_back(contents[i]);
        return v;
    };
    // model indices: 0 is G on A; 1 + (j - a) is G on C \ {c_j}; 1 + (N - a) + i is G on (A \ {c_i}) + {p}
    auto model = [&](std::size_t index) {
        return std::pair{inner_root / ("model" + std::to_string(index + 1)), seed + 7919 * static_cast<std::uint64_t>(index + 1)};
    };
    stargan::gate_plan plan;
    auto add = [&](std::vector<std::string> group, std::size_t scored_by) {
        std::sort(group.begin(), group.end());
        const auto [dir, s] = model(scored_by);
        plan.groups.push_back(std::move(group));
        plan.dirs.push_back(dir);
        plan.seeds.push_back(s);
    };
    if (k >= a) {  // held out from C: groups A (scored by G on C \ {k}) and C \ {k} (scored by G on A)
        add(range(0, a, N), 1 + (k - a));
        add(range(a, N, k), 0);
    } else {  // held out from A: groups (A \ {k}) + {p} (scored by G on C \ {p}) and C \ {p} (scored by G on (A \ {k}) + {p})
        auto g0 = range(0, a, k);
        g0.push_back(contents[p]);
        add(std::move(g0), 1);
        add(range(a, N, p), 1 + (N - a) + k);
    }
    return plan;
}

/// @brief The ring plan's inner groups for the fold holding out `held` (see the header comment): for an odd
/// number of contents N, the runs of (N - 1) / 2 contents that follow `held` on the ring of sorted contents;
/// for an even N, shared_gate_plan()'s.
/// @param contents every content of the data set, sorted
/// @param inner_root where the shared inner models live (<report>/inner)
/// @param seed the evaluation's base seed (train.seed)
/// @return the plan, or nothing for fewer than 3 contents (no two inner groups to form)
/// @throws value_error when `held` is not one of `contents`.
inline std::optional<stargan::gate_plan> ring_gate_plan(const std::vector<std::string>& contents, const std::string& held,
                                                        const std::filesystem::path& inner_root, std::uint64_t seed)
{
    const std::size_t N = contents.size();
    if (N % 2 == 0) return shared_gate_plan(contents, held, inner_root, seed);
    const auto at = std::find(contents.begin(), contents.end(), held);
    if (at == contents.end()) throw value_error("eval: ring gate plan: content '" + held + "' is not in the data set");
    if (N < 3) return std::nullopt;
    const std::size_t a = (N - 1) / 2;
    const std::size_t k = static_cast<std::size_t>(at - contents.begin());
    auto run = [&](std::size_t s) {  // R_s, sorted
        std::vector<std::string> v;
        for (std::size_t i = 0; i < a; ++i) v.push_back(contents[(s + i) % N]);
        std::sort(v.begin(), v.end());
        return v;
    };
    const std::size_t s0 = (k + 1) % N, s1 = (k + a + 1) % N;
    stargan::gate_plan plan;
    // group R_{s0} is scored by the G trained on R_{s1}, and the other way round
    for (const auto& [group, scored_by] : {std::pair{s0, s1}, std::pair{s1, s0}}) {
        plan.groups.push_back(run(group));
        plan.dirs.push_back(inner_root / ("ring" + std::to_string(scored_by + 1)));
        plan.seeds.push_back(seed + 7919 * static_cast<std::uint64_t>(scored_by + 1));
    }
    return plan;
}

/// @brief One training of an evaluation's plan: an inner model of the gate or a fold's final G.
struct training_job {
    std::string label;               ///< for the progress lines
    std::function<void()> run;       ///< trains (or finds already trained) the model
    std::vector<std::size_t> after;  ///< jobs that must be done first
    double seconds = 0;              ///< how long run() took
    std::filesystem::path output;    ///< the file run() leaves (in a group, every process checks it after the job's wave)
    /// when set, called instead of run() with the job slots the job may use: 1, or every slot for the last job to
    /// start (no job is left for the other slots, whose jobs are ending); a job whose result does not depend on
    /// its thread count can take that many times its threads
    std::function<void(std::size_t)> run_on_slots = {};
};

/// @brief Runs `jobs_list` with up to `jobs` at once, each job only after those it names in `after`, printing a
/// line with the count done and an ETA after each. The last job to start is offered all `jobs` slots
/// (training_job::run_on_slots). The first error stops handing out jobs; it is rethrown once the running ones end.
/// @throws value_error for a job waiting on itself or on a later or unknown job (the list must be in an order
/// that can run); the first error of a job otherwise.
inline void run_training_jobs(std::vector<training_job>& jobs_list, std::size_t jobs, std::FILE* progress_out, const std::string& what)
{
    for (std::size_t i = 0; i < jobs_list.size(); ++i)
        for (std::size_t d : jobs_list[i].after)
            if (d >= i) throw value_error("eval: training plan: job '" + jobs_list[i].label + "' waits on a job that is not before it");
    const std::size_t n = jobs_list.size();
    std::vector<char> started(n, 0), done(n, 0);
    std::size_t finished = 0;
    std::exception_ptr error;
    std::mutex m;
    std::condition_variable cv;
    progress bar(what, static_cast<long>(n), progress_out, 0.0);
    auto next = [&]() -> std::optional<std::size_t> {  // under m: the first job not started whose waits are done
        for (std::size_t i = 0; i < n; ++i) {
            if (started[i]) continue;
            bool ready = true;
            for (std::size_t d : jobs_list[i].after) ready = ready && done[d];
            if (ready) return i;
        }
        return std::nullopt;
    };
    auto worker = [&] {
        for (;;) {
            std::size_t i = 0, slots = 1;
            {
                std::unique_lock lock(m);
                std::optional<std::size_t> pick;
                cv.wait(lock, [&] {
                    if (error) return true;
                    pick = next();
                    return pick.has_value() || std::all_of(started.begin(), started.end(), [](char s) { return s != 0; });
                });
                if (error || !pick) return;
                i = *pick;
                started[i] = 1;
                slots = std::all_of(started.begin(), started.end(), [](char s) { return s != 0; }) ? std::max<std::size_t>(jobs, 1) : 1;
            }
            const auto t0 = std::chrono::steady_clock::now();
            try {
                if (jobs_list[i].run_on_slots)
                    jobs_list[i].run_on_slots(slots);
                else
                    jobs_list[i].run();
            } catch (...) {
                std::lock_guard lock(m);
                if (!error) error = std::current_exception();
                cv.notify_all();
                return;
            }
            std::lock_guard lock(m);
            jobs_list[i].seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            done[i] = 1;
            ++finished;
            char status[200];
            std::snprintf(status, sizeof status, "%s (%.1f min)", jobs_list[i].label.c_str(), jobs_list[i].seconds / 60);
            bar.update(static_cast<long>(finished), status);
            cv.notify_all();
        }
    };
    const std::size_t T = std::max<std::size_t>(1, std::min(jobs, n));
    std::vector<std::thread> threads;
    for (std::size_t t = 1; t < T; ++t) threads.emplace_back(worker);
    worker();
    for (auto& t : threads) t.join();
    if (error) std::rethrow_exception(error);
}

/// @brief The process of a group of `ranks` that runs job `index` of a wave (the wave's jobs counted in plan order
/// from 0): index mod ranks, so the processes take the wave's jobs in turn.
inline std::size_t wave_rank(std::size_t index, std::size_t ranks) noexcept { return ranks == 0 ? 0 : index % ranks; }

/// @brief The wave of each job of a plan: 0 for a job that waits on none, else one after the latest wave it waits on.
/// @throws value_error for a job waiting on itself or on a later or unknown job.
inline std::vector<std::size_t> job_waves(const std::vector<training_job>& jobs_list)
{
    std::vector<std::size_t> wave(jobs_list.size(), 0);
    for (std::size_t i = 0; i < jobs_list.size(); ++i)
        for (std::size_t d : jobs_list[i].after) {
            if (d >= i) throw value_error("eval: training plan: job '" + jobs_list[i].label + "' waits on a job that is not before it");
            wave[i] = std::max(wave[i], wave[d] + 1);
        }
    return wave;
}

namespace detail {

/// FNV-1a of the jobs' labels and outputs, in plan order: equal on every process that planned the same jobs. Kept to
/// 32 bits, so that it travels exactly as a double.
inline std::uint32_t plan_fingerprint(const std::vector<training_job>& jobs_list)
{
    std::uint32_t h = 2166136261u;
    auto add = [&](const std::string& text) {
        for (unsigned char c : text) h = (h ^ c) * 16777619u;
        h = (h ^ 0xffu) * 16777619u;  // a separator no label holds
    };
    for (const auto& j : jobs_list) add(j.label), add(j.output.string());
    return h;
}

}  // namespace detail

/// @brief Runs `jobs_list` over the processes of `group` in waves (see the header comment): in each wave, this
/// process runs the jobs wave_rank() gives it, `jobs` at a time (run_training_jobs(), printing to progress_out); then
/// every job's seconds are gathered from the process that ran it (a collective: also the wave's barrier) and every
/// process checks that every job of the wave left its output. Every process of the group calls it with the same plan.
/// On return every job's `seconds` holds the time it took on its process.
/// @throws value_error, on every process, when the processes planned different jobs (other data or report folders) or
/// a job's output is not there after its wave (the report folder is not shared, or a process skipped it); the first
/// error of this process's own jobs, on this process alone: the others then wait for it at the wave's end, so the
/// caller ends them (the CLI: MPI_Abort through dist::mpi_runtime::abort_all).
inline void run_training_waves(std::vector<training_job>& jobs_list, dist::process_group& group, std::size_t jobs,
                               std::FILE* progress_out, const std::string& what)
{
    const std::size_t R = group.ranks(), me = group.rank();
    const auto wave = job_waves(jobs_list);
    {  // every process planned the same jobs, or none starts
        const double mine[2] = {static_cast<double>(jobs_list.size()), static_cast<double>(detail::plan_fingerprint(jobs_list))};
        std::vector<double> all(2 * R);
        group.all_gather(mine, all);
        for (std::size_t r = 0; r < R; ++r)
            if (all[2 * r] != mine[0] || all[2 * r + 1] != mine[1])
                throw value_error("eval: process " + std::to_string(r) + " of " + std::to_string(R) + " planned " +
                                  std::to_string(static_cast<std::size_t>(all[2 * r])) + " trainings, process " + std::to_string(me) +
                                  " " + std::to_string(jobs_list.size()) + (all[2 * r] == mine[0] ? " other ones" : "") +
                                  ": every process needs the same data, options and report folder (a file system all of them see)");
    }
    const std::size_t waves = jobs_list.empty() ? 0 : *std::max_element(wave.begin(), wave.end()) + 1;
    for (std::size_t w = 0; w < waves; ++w) {
        std::vector<std::size_t> in_wave, mine;  // the wave's jobs in plan order; those of this process
        for (std::size_t i = 0; i < jobs_list.size(); ++i)
            if (wave[i] == w) {
                if (wave_rank(in_wave.size(), R) == me) mine.push_back(i);
                in_wave.push_back(i);
            }
        if (progress_out)
            std::fprintf(progress_out, "eval: wave %zu of %zu: %zu trainings dealt round %zu processes, %zu on process %zu, %zu at a time\n",
                         w + 1, waves, in_wave.size(), R, mine.size(), me, jobs),
                std::fflush(progress_out);
        std::vector<training_job> share;  // what waits on earlier waves is done: their barrier has passed
        for (std::size_t i : mine)
            share.push_back({jobs_list[i].label, jobs_list[i].run, {}, 0, jobs_list[i].output, jobs_list[i].run_on_slots});
        run_training_jobs(share, jobs, progress_out, what + " (wave " + std::to_string(w + 1) + ")");
        std::vector<double> seconds(in_wave.size(), 0.0), all(in_wave.size() * R);
        for (std::size_t k = 0; k < mine.size(); ++k)
            seconds[static_cast<std::size_t>(std::find(in_wave.begin(), in_wave.end(), mine[k]) - in_wave.begin())] = share[k].seconds;
        group.all_gather(seconds, all);
        double longest = 0;
        for (std::size_t k = 0; k < in_wave.size(); ++k) {
            auto& job = jobs_list[in_wave[k]];
            const std::size_t owner = wave_rank(k, R);
            job.seconds = all[owner * in_wave.size() + k];
            longest = std::max(longest, job.seconds);
            if (!job.output.empty() && !path_exists(job.output))
                throw value_error("eval: process " + std::to_string(owner) + " of " + std::to_string(R) + " was to leave " +
                                  job.output.string() + " ('" + job.label + "'), which process " + std::to_string(me) +
                                  " does not find: the report folder must be on a file system every process sees");
        }
        if (progress_out)
            std::fprintf(progress_out, "eval: wave %zu of %zu done on every process (longest training %.1f min)\n", w + 1, waves, longest / 60),
                std::fflush(progress_out);
    }
}

}  // namespace handemo::eval
