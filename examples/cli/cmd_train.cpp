// `handemo train --data DIR --out MODEL [...]`: trains a StarGAN emotion-transfer model (Section 3.3 of
// the hand paper) on a folder of labelled BVH/CSV clips and writes checkpoints, the loss log and a loss plot.
#include "registry.hpp"

#include <handemo/render/svg.hpp>
#include <handemo/stargan.hpp>

#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

namespace {

struct train_cli {
    std::string data, out, config = "hand-embedded";
    std::vector<std::string> exclude;
    bool resume = false;
    double lr = -1;
    handemo::stargan::train_options opt;
};

void run_train(train_cli& o)
{
    using namespace handemo;
    using namespace handemo::stargan;
    namespace fs = std::filesystem;
    if (o.lr >= 0) o.opt.g_lr = o.opt.d_lr = o.lr;
    o.opt.validate();
    load_options lo;
    lo.exclude_contents = o.exclude;
    const auto clips = load_folder(o.data, lo);
    std::cout << "train: " << clips.size() << " clips from " << o.data;
    if (!o.exclude.empty()) {
        std::cout << " (left out:";
        for (const auto& e : o.exclude) std::cout << " " << e;
        std::cout << ")";
    }
    std::cout << ", configuration " << o.config << ", " << o.opt.iters << " iterations\n";
    with_config(o.config, [&]<stargan_config Config>(const config_info& info) {
        std::optional<angle_range> range;
        if (o.resume) {
            const fs::path ck = fs::path(o.out) / "checkpoint.safetensors";
            if (!fs::exists(ck)) throw io_error("train: --resume: no checkpoint at " + ck.string());
            range = read_checkpoint(ck).second.range;  // a resumed run keeps its Eq. 3 range
        }
        trainer<Config> tr(info, prepare_data<Config>(clips, info, range), o.opt);
        tr.run(o.out, o.resume);
        const std::string svg = plot_losses_svg(loss_log_csv(tr.log()), {.title = "handemo train " + info.name + " (" + o.data + ")"});
        write_file_atomic(fs::path(o.out) / "losses.svg", svg);
        std::cout << "train: " << tr.step() << " iterations done; wrote " << (fs::path(o.out) / "checkpoint.safetensors").string()
                  << " (G, D, Adam, RNG, range, tempo), generator.safetensors (PyTorch names), log.csv, losses.svg, range.json\n";
        std::cout << "train: tempo factors (duration relative to " << info.neutral << "):";
        for (std::size_t k = 0; k < info.domains; ++k) std::cout << " " << info.domain_names[k] << " " << tr.data().tempo[k];
        std::cout << "\n";
    });
}

}  // namespace

static handemo::cli::add_command reg_train{40, [](CLI::App& app) {
    auto* sub = app.add_subcommand("train", "Train a StarGAN emotion-transfer model on a folder of labelled clips");
    auto o = std::make_shared<train_cli>();
    auto& t = o->opt;
    sub->add_option("--data", o->data, "Folder of <prefix>_<content>_<emotion>_<take>.bvh|csv clips or with a manifest.csv")->required();
    sub->add_option("--out", o->out, "Model folder (checkpoint.safetensors, log.csv, losses.svg, ...)")->required();
    sub->add_option("--config", o->config, "hand-embedded | hand-paper | body-embedded | hand-tiny")->capture_default_str();
    sub->add_option("--iters", t.iters, "D iterations (G every --n-critic)")->capture_default_str();
    sub->add_option("--exclude-content", o->exclude, "Leave this content (motion type) out of training; repeatable");
    sub->add_option("--threads", t.threads, "Worker threads (0: all cores)")->capture_default_str();
    sub->add_option("--seed", t.seed, "Random seed; same seed and threads give bitwise the same weights")->capture_default_str();
    sub->add_flag("--resume", o->resume, "Continue from MODEL/checkpoint.safetensors");
    sub->add_option("--lr", o->lr, "Learning rate of both G and D (default 1e-4)");
    sub->add_option("--g-lr", t.g_lr, "Learning rate of G")->capture_default_str();
    sub->add_option("--d-lr", t.d_lr, "Learning rate of D")->capture_default_str();
    sub->add_option("--lambda-cls", t.lambda_cls, "Weight of the domain classification loss")->capture_default_str();
    sub->add_option("--lambda-rec", t.lambda_rec, "Weight of the reconstruction loss")->capture_default_str();
    sub->add_option("--lambda-gp", t.lambda_gp, "Weight of the gradient penalty")->capture_default_str();
    sub->add_option("--n-critic", t.n_critic, "D iterations per G iteration")->capture_default_str();
    sub->add_option("--beta1", t.beta1, "Adam beta1")->capture_default_str();
    sub->add_option("--beta2", t.beta2, "Adam beta2")->capture_default_str();
    sub->add_option("--decay-start", t.decay_start, "Fraction of training after which the learning rate decays linearly to 0")->capture_default_str();
    sub->add_option("--checkpoint-every", t.checkpoint_every, "Iterations between checkpoints")->capture_default_str();
    sub->add_option("--log-every", t.log_every, "Iterations between rows of log.csv")->capture_default_str();
    sub->callback([o] { run_train(*o); });
}};
