// `handemo demo --out DIR`: the main job end to end. Generates the synthetic hand dataset, trains the
// hand-embedded StarGAN leaving one motion type out, transfers that unseen type's neutral take to every
// other emotion, and writes BVH, BMP and filmstrip outputs with a comparison against the real clips.
#pragma once

#include "../registry.hpp"
#include "options.hpp"

#include <handemo/metrics/baselines.hpp>
#include <handemo/metrics/compare.hpp>
#include <handemo/image.hpp>
#include <handemo/motion.hpp>
#include <handemo/image/keyframe_image.hpp>
#include <handemo/render.hpp>
#include <handemo/stargan.hpp>
#ifdef HANDEMO_HAVE_GIF
#include <handemo/gif.hpp>
#endif

#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <string>

namespace handemo::cli::demo_cmd {

struct demo_cli {
    std::string out = "demo";
    std::string config = "hand-embedded";
    std::string held_out = "pushing";
    int takes = 3;
    handemo::cli::train_overrides ov;
    handemo::stargan::train_options opt;
};

inline void run_demo(demo_cli& o)
{
    using namespace handemo;
    using namespace handemo::stargan;
    namespace fs = std::filesystem;
    const fs::path root(o.out), data = root / "data", model = root / "model", outdir = root / "transfer";
    const hand_motion held = hand_motion_from_string(o.held_out);
    finish_train_options(o.opt, o.ov);

    // 1. synthetic dataset
    std::cout << "demo 1/4: synthesising " << o.takes << " takes x 7 motions x 5 emotions into " << data.string() << "\n";
    fs::create_directories(data);
    for (const auto& it : synthesize_dataset(o.takes, o.opt.seed)) write_bvh(data / (it.file_stem + ".bvh"), it.c);

    // 2. train, leaving the held-out motion type out
    load_options lo;
    lo.exclude_contents = {std::string(to_string(held))};
    const auto clips = load_folder(data, lo);
    std::cout << "demo 2/4: training " << o.config << " on " << clips.size() << " clips (" << to_string(held)
              << " left out), " << o.opt.iters << " iterations, lr " << o.opt.g_lr << ", lambda_cls " << o.opt.lambda_cls << "\n";
    with_config(o.config, [&]<stargan_config Config>(const config_info& info) {
        const auto trp = train_model<Config>(clips, info, o.opt, model);
        auto& tr = *trp;
        write_file_atomic(model / "losses.svg", plot_losses_svg(loss_log_csv(tr.log()), {.title = "demo: training losses"}));
    });

    // 3. transfer the unseen motion's neutral take to every other emotion
    const auto m = load_model(model);
    fs::create_directories(outdir);
    const std::string mname(to_string(held));
    const clip input = read_bvh(data / (file_stem(held, emotion::neutral, 0) + ".bvh"));
    std::cout << "demo 3/4: transferring the unseen '" << mname << "' neutral take to every emotion\n";
    std::vector<clip> strip, truth;
    std::vector<std::string> titles;
    // the baselines StarGAN has to beat, fitted on the same training clips
    const auto offset = metrics::mean_offset_baseline<9>::fit(clips, m->info().neutral);
    std::printf("  keyframe RMSE to the real clip of each emotion (deg), lower is better:\n");
    std::printf("  %-8s %6s %7s %9s %9s %12s %6s %11s %12s\n", "emotion", "tempo", "frames", "stargan", "identity",
                "mean-offset", "wins", "ROM out/in", "ROM real/in");
    double sum_s = 0, sum_i = 0, sum_o = 0;
    int wins = 0, n = 0;
    std::string detail_lines;  // the detail layer's full-rate speed, printed after the table
    const double speed_in = metrics::mean_speed(input);
    for (const auto& e : m->info().domains) {
        if (e == m->info().neutral) {
            strip.push_back(input);
            truth.push_back(input);
            titles.push_back("input (neutral)");
            continue;
        }
        const auto r = m->transfer(input, e);
        write_bvh(outdir / (mname + "_" + e + ".bvh"), r.motion);
        write_bmp(outdir / (mname + "_" + e + ".bmp"), to_image(r.image));
        const clip real = read_bvh(data / (file_stem(held, emotion_from_string(e), 0) + ".bvh"));
        const double rs = metrics::keyframe_rmse(r.motion, real), ri = metrics::keyframe_rmse(input, real),
                     ro = metrics::keyframe_rmse(offset.transfer(input, e, r.tempo), real);
        const bool win = rs < ri && rs < ro;
        sum_s += rs, sum_i += ri, sum_o += ro, wins += win, ++n;
        std::printf("  %-8s %6.2f %7zu %9.2f %9.2f %12.2f %6s %11.2f %12.2f\n", e.c_str(), r.tempo, r.motion.frames, rs, ri, ro,
                    win ? "yes" : "no", metrics::range_of_motion(r.motion) / metrics::range_of_motion(input),
                    metrics::range_of_motion(real) / metrics::range_of_motion(input));
        if (m->has_detail()) {
            // the same transfer with the detail layer (`transfer --detail`): full-rate speed against the real clip's
            const clip d = m->add_detail(r.motion, input, e);
            write_bvh(outdir / (mname + "_" + e + "_detail.bvh"), d);
            char line[160];
            std::snprintf(line, sizeof line, "  %-8s %9.2f %9.2f %9.2f\n", e.c_str(), metrics::mean_speed(r.motion) / speed_in,
                          metrics::mean_speed(d) / speed_in, metrics::mean_speed(real) / speed_in);
            detail_lines += line;
        }
        strip.push_back(r.motion);
        truth.push_back(real);
        titles.push_back(e);
    }
    std::printf("  %-8s %6s %7s %9.2f %9.2f %12.2f %3d/%-2d\n", "mean", "", "", sum_s / n, sum_i / n, sum_o / n, wins, n);
    std::cout << "  " << (sum_s < sum_i && sum_s < sum_o ? "StarGAN beats both baselines on the unseen motion"
                                                         : "StarGAN does NOT beat both baselines on the unseen motion")
              << " (preset " << o.ov.preset << ")\n";
    if (!detail_lines.empty())
        std::printf("  full-rate speed, output / input (what 9 keyframes miss; the detail layer puts the input's own detail back):\n"
                    "  %-8s %9s %9s %9s\n%s", "emotion", "stargan", "+detail", "real", detail_lines.c_str());
    // 4. pictures
    filmstrip_options fo;
    fo.rows = 6;
    fo.cell_width = fo.cell_height = 160;
    fo.titles = titles;
    write_png(outdir / "filmstrip.png", render_filmstrip(strip, fo));
    for (auto& t : fo.titles)
        if (t != "input (neutral)") t = "real " + t;
    write_png(outdir / "filmstrip_real.png", render_filmstrip(truth, fo));
#ifdef HANDEMO_HAVE_GIF
    {  // the input and every transfer playing side by side in real time (tempo shows as speed), looping
        animation_options ao;
        ao.strip = fo;
        ao.strip.titles = titles;
        ao.strip.cell_width = ao.strip.cell_height = 140;
        write_gif(outdir / "filmstrip.gif", filmstrip_animation(strip, ao));
    }
#endif
    {  // the transfers playing side by side, and the real clips under them, in one offline page
        std::vector<clip> both = strip;
        both.insert(both.end(), truth.begin(), truth.end());
        viewer_options vo;
        vo.titles = titles;
        for (const auto& t : titles) vo.titles.push_back(t == "input (neutral)" ? t : "real " + t);
        vo.normalised_time = true;
        vo.columns = strip.size();  // each transfer above its real clip
        vo.width = 1200;
        vo.height = 300;
        vo.page_title = "handemo demo: unseen '" + mname + "' transferred (top) and real (bottom)";
        write_file_atomic(outdir / "view.html", render_viewer_html(both, vo));
    }
    std::cout << "demo 4/4: wrote\n"
              << "  " << outdir.string() << "/" << mname << "_<emotion>.bvh   transferred motions (open in Blender or three.js)\n"
              << "  " << outdir.string() << "/" << mname << "_<emotion>_detail.bvh   the same with the detail layer (transfer --detail)\n"
              << "  " << outdir.string() << "/" << mname << "_<emotion>.bmp   the transfers' motion images (their keyframes, Eq. 3)\n"
              << "  " << (outdir / "filmstrip.png").string() << "   angry | happy | input (neutral) | sad | fearful\n"
              << "  " << (outdir / "filmstrip_real.png").string() << "   the real clips of those emotions, for comparison\n"
#ifdef HANDEMO_HAVE_GIF
              << "  " << (outdir / "filmstrip.gif").string() << "   the input and the transfers moving (animated GIF)\n"
#endif
              << "  " << (outdir / "view.html").string() << "   all of them playing (open in a browser; works offline)\n"
              << "  " << (model / "losses.svg").string() << ", log.csv, checkpoint.safetensors   the trained model\n";
}

}  // namespace handemo::cli::demo_cmd

static handemo::cli::add_command reg_demo{1, [](CLI::App& app) {
    auto* sub = app.add_subcommand("demo", "Main job: synthesise data, train leaving one motion type out, transfer it to every emotion");
    auto o = std::make_shared<handemo::cli::demo_cmd::demo_cli>();
    o->opt.iters = 2000;
    o->opt.checkpoint_every = 500;
    sub->add_option("--out", o->out, "Output folder")->capture_default_str();
    sub->add_option("--config", o->config, "StarGAN configuration")->capture_default_str();
    sub->add_option("--held-out", o->held_out, "Motion type left out of training and transferred")->capture_default_str();
    sub->add_option("--takes", o->takes, "Takes per motion/emotion pair")->capture_default_str();
    sub->add_option("--iters", o->opt.iters, "Training iterations")->capture_default_str();
    handemo::cli::add_train_options(sub, o->opt, o->ov);
    sub->add_option("--seed", o->opt.seed, "Seed of the data and the training")->capture_default_str();
    sub->callback([o] { handemo::cli::demo_cmd::run_demo(*o); });
}};
