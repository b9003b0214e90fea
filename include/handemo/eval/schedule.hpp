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
// train_all() trains every inner model and every fold's final G first, `jobs` of them at once on their own
// threads, each with train.threads threads (1 when it is 0 and jobs > 1); a final G waits for its two inner
// models. Training is deterministic for a seed and thread count, so the models are bit for bit those of
// training them one after another (a test checks it), and the folds are then scored one by one with them.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/core/io.hpp>
#include <handemo/core/progress.hpp>
#include <handemo/stargan/dataset.hpp>
#include <handemo/stargan/gate.hpp>
#include <handemo/stargan/train.hpp>

#include <algorithm>
#include <chrono>
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
    shared,   ///< the shared plan (schedule.hpp): N + 1 inner models for N folds
    per_fold  ///< each fold's sorted training contents dealt round the groups (`handemo train`'s own): 2 N
};

/// @brief "shared" or "per-fold".
inline const char* to_string(gate_groups g) noexcept { return g == gate_groups::shared ? "shared" : "per-fold"; }

/// @brief Parses "shared" or "per-fold".
/// @throws value_error naming the value.
inline gate_groups parse_gate_groups(const std::string& s)
{
    if (s == "shared") return gate_groups::shared;
    if (s == "per-fold") return gate_groups::per_fold;
    throw value_error("eval: --gate-groups '" + s + "' is not 'shared' or 'per-fold'");
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

/// @brief One training of an evaluation's plan: an inner model of the gate or a fold's final G.
struct training_job {
    std::string label;               ///< for the progress lines
    std::function<void()> run;       ///< trains (or finds already trained) the model
    std::vector<std::size_t> after;  ///< jobs that must be done first
    double seconds = 0;              ///< how long run() took
};

/// @brief Runs `jobs_list` with up to `jobs` at once, each job only after those it names in `after`, printing a
/// line with the count done and an ETA after each. The first error stops handing out jobs; it is rethrown once
/// the running ones end.
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
            std::size_t i = 0;
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
            }
            const auto t0 = std::chrono::steady_clock::now();
            try {
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

}  // namespace handemo::eval
