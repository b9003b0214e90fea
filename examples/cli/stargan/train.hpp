// `handemo train --data DIR --out MODEL [...]`: trains a StarGAN emotion-transfer model (Section 3.3 of
// the hand paper) on a folder of labelled BVH/CSV clips and writes checkpoints, the loss log and a loss plot.
#pragma once

#include "../registry.hpp"
#include "options.hpp"

#include <handemo/render/svg.hpp>
#include <handemo/stargan.hpp>

#include <filesystem>
#include <iostream>
#include <ostream>
#include <memory>
#include <string>
#include <vector>

namespace handemo::cli::train_cmd {

struct train_cli {
    std::string data, out, config = "hand-embedded";
    std::vector<std::string> exclude;
    bool resume = false;
    bool mpi = false;  ///< --mpi: one half of each batch per MPI process (cmd_mpi.cpp)
    handemo::cli::train_overrides ov;
    handemo::stargan::train_options opt;
};

inline void run_train(train_cli& o)
{
    using namespace handemo;
    using namespace handemo::stargan;
    namespace fs = std::filesystem;
    finish_train_options(o.opt, o.ov);
    if (o.mpi) {
        o.opt.exchange = handemo::cli::mpi().start();
        // every configuration trains batches of the same size, cut into at most max_shards() parts: one per process
        using any_trainer = trainer<hand_tiny>;
        if (o.opt.exchange->ranks() > any_trainer::max_shards())
            throw value_error("train: --mpi: " + std::to_string(o.opt.exchange->ranks()) + " processes, but a batch of " +
                              std::to_string(any_trainer::N) + " is cut into at most " + std::to_string(any_trainer::max_shards()) +
                              " parts, one per process");
    }
    const bool writer = writes_files(o.opt);  // with several processes: rank 0 writes and prints, the others are silent
    if (!writer) o.opt.progress_out = nullptr;
    std::ostream silent(nullptr);
    std::ostream& out = writer ? std::cout : silent;
    load_options lo;
    lo.exclude_contents = o.exclude;
    const auto clips = load_folder(o.data, lo);
    out << "train: " << clips.size() << " clips from " << o.data;
    if (!o.exclude.empty()) {
        out << " (left out:";
        for (const auto& e : o.exclude) out << " " << e;
        out << ")";
    }
    out << ", configuration " << o.config << ", preset " << o.ov.preset << ", " << o.opt.iters << " iterations\n";
    with_config(o.config, [&]<stargan_config Config>(const config_info& info) {
        std::optional<angle_range> range;
        if (o.resume) {
            const fs::path ck = fs::path(o.out) / "checkpoint.safetensors";
            if (!fs::exists(ck)) throw io_error("train: --resume: no checkpoint at " + ck.string());
            range = read_checkpoint(ck).second.range;  // a resumed run keeps its Eq. 3 range
        }
        gate_fit gate;
        const auto trp = train_model<Config>(clips, info, o.opt, o.out, o.resume, range, &gate);
        auto& tr = *trp;
        const std::string svg = plot_losses_svg(loss_log_csv(tr.log()), {.title = "handemo train " + info.name + " (" + o.data + ")"});
        if (writer) write_file_atomic(fs::path(o.out) / "losses.svg", svg);
        out << "train: " << tr.step() << " iterations done; wrote " << (fs::path(o.out) / "checkpoint.safetensors").string()
                  << " (G, D, Adam, RNG, range, tempo), generator.safetensors (PyTorch names), log.csv, losses.svg, range.json\n";
        if (o.opt.amplitude) {
            out << "train: amplitude factors (excursion relative to " << info.neutral << "):";
            for (std::size_t k = 0; k < info.domains; ++k) out << " " << info.domain_names[k] << " " << tr.data().amplitude[k];
            const auto& d = tr.data();
            const bool ends = d.amplitude_anchor == amplitude_anchor::ends;
            out << " about the " << anchor_name(d.amplitude_anchor)
                << (o.opt.amplitude_estimator == "channel" ? ", each the median ratio of the channels that move," : "")
                << " (leave-one-content-out on the training clips: RMSE "
                << d.amplitude_check.second << " deg scaled vs " << d.amplitude_check.first << " unscaled" << (ends ? ", both with the posture prior" : "")
                << (d.amplitude_check.second < d.amplitude_check.first ? ")" : "; not used)");
            if (std::isfinite(d.amplitude_anchor_check.first))
                out << "; the anchor chosen by the same check with the prior: " << d.amplitude_anchor_check.first << " deg about the mean, "
                    << d.amplitude_anchor_check.second << " about the ends";
            out << "\n";
        }
        if (o.opt.lag) {
            const auto& lf = tr.data().lag;
            out << "train: joint lag (keyframe intervals, leave-one-content-out on the training clips: excursion RMSE with / without):";
            for (std::size_t k = 0; k < info.domains; ++k) {
                if (info.domain_names[k] == info.neutral) continue;
                double lo = 0, hi = 0;
                for (double v : lf.lag[k]) lo = std::min(lo, v), hi = std::max(hi, v);
                out << " " << info.domain_names[k] << " " << (lf.kept[k] ? "kept" : "not used") << " (" << lf.check[k].second << " / "
                    << lf.check[k].first << " deg";
                if (lf.kept[k]) out << ", lags " << lo << " to " << hi;
                out << ")";
            }
            out << "\n";
        }
        if (!gate.rows.empty()) {
            out << "train: change gate (weight of G's posture / motion change / posture prior per target, chosen on held-out "
                         "training contents; "
                      << (fs::path(o.out) / "gate" / "gate.csv").string() << "):";
            for (const auto& r : gate.rows) out << " " << r.target << " " << r.posture << "/" << r.motion << "/" << r.prior;
            out << "\n";
        }
        out << "train: tempo factors (duration relative to " << info.neutral << "):";
        for (std::size_t k = 0; k < info.domains; ++k) out << " " << info.domain_names[k] << " " << tr.data().tempo[k];
        out << "\n";
        if (o.opt.tempo_neighbours) {
            const auto& tn = tr.data().tempo_table;
            out << "train: tempo neighbours: "
                << (tn.empty() ? std::string("the learned factors kept") : "each input takes its " + std::to_string(tn.k) + " nearest training contents'");
            if (!tn.errors.empty() && std::isfinite(tn.errors.front())) {
                out << " (left-out error: learned " << tn.errors.front();
                for (std::size_t i = 0; i < stargan::tempo_neighbour_grid.size(); ++i) out << ", " << stargan::tempo_neighbour_grid[i] << ": " << tn.errors[i + 1];
                out << ")";
            }
            out << "\n";
        }
    });
}

}  // namespace handemo::cli::train_cmd

static handemo::cli::add_command reg_train{40, [](CLI::App& app) {
    auto* sub = app.add_subcommand("train", "Train a StarGAN emotion-transfer model on a folder of labelled clips");
    auto o = std::make_shared<handemo::cli::train_cmd::train_cli>();
    auto& t = o->opt;
    sub->add_option("--data", o->data, "Folder of <prefix>_<content>_<emotion>_<take>.bvh|csv clips or with a manifest.csv")->required();
    sub->add_option("--out", o->out, "Model folder (checkpoint.safetensors, log.csv, losses.svg, ...)")->required();
    sub->add_option("--config", o->config, "hand-embedded | hand-paper | body-embedded | hand-micro | hand-tiny")->capture_default_str();
    sub->add_option("--iters", t.iters, "D iterations (G every --n-critic)")->capture_default_str();
    sub->add_option("--exclude-content", o->exclude, "Leave this content (motion type) out of training; repeatable");
    sub->add_option("--seed", t.seed, "Random seed; the same seed and shards (--shards) give bitwise the same weights on any thread count")->capture_default_str();
    sub->add_flag("--resume", o->resume, "Continue from MODEL/checkpoint.safetensors");
    if (handemo::cli::mpi().start)
        sub->add_flag("--mpi", o->mpi,
                      "Run as one of 2 MPI processes (mpirun -np 2, srun): each computes one half of every batch, the same model "
                      "as --shards 2 byte for byte; rank 0 prints and writes the files");
    handemo::cli::add_train_options(sub, t, o->ov);
    sub->add_option("--checkpoint-every", t.checkpoint_every, "Iterations between checkpoints")->capture_default_str();
    sub->add_option("--log-every", t.log_every, "Iterations between rows of log.csv")->capture_default_str();
    sub->callback([o] { handemo::cli::train_cmd::run_train(*o); });
}};
