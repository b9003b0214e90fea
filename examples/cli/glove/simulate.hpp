// `handemo glove simulate --glove senso|opengloves|5dt|P.json --out raw.bin [--motion M] [--emotion E] [--seconds N]`:
// a raw report stream of a simulated glove wearing a synthetic take (synth.hpp): the flat hand, a fist
// (gloves with bend sensors), then the motion looped; the messages are the glove's own (JSON lines, alpha
// lines, HID reports); optionally with lost reports and garbage. For trying the glove commands without a
// glove (`--replay raw.bin`) and for their tests.
#pragma once

#include "common.hpp"

#include <handemo/motion/synth.hpp>

#include <algorithm>

#include <iostream>

namespace handemo::cli::glove_cmd {

struct simulate_cli {
    source_options src;
    std::string out, motion = "gripping", emotion = "neutral";
    double seconds = 4, flat = 1;
    std::size_t drop_every = 0, garbage_every = 0;
    std::uint64_t seed = 1;
};

inline void run_simulate(const simulate_cli& o)
{
    const auto c = o.src.choice();
    const auto& p = c.profile;
    const bool lines = c.kind == "senso" || c.kind == "opengloves";
    const clip take = synthesize(hand_motion_from_string(o.motion), emotion_from_string(o.emotion), 0, o.seed, p.rate_hz);
    const glove_simulator sim(p, o.seed);
    const skeleton hand = hand_skeleton();
    std::vector<double> flat(hand_joint_count * 3, 0.0), fist = flat;
    bool has_fist = false;
    for (const auto* f : p.flexes)
        if (f->fist_calibrated) fist[hand.index_of(f->bone) * 3 + static_cast<std::size_t>(f->rotation_axis)] = f->fist_angle, has_fist = true;
    const double fist_seconds = has_fist ? o.flat : 0;
    raw_writer w(o.out);
    const auto n = static_cast<std::uint64_t>(std::llround((o.flat + fist_seconds + o.seconds) * p.rate_hz));
    std::size_t dropped = 0, garbage = 0, written = 0;
    for (std::uint64_t tick = 0; tick < n; ++tick) {
        const double t = static_cast<double>(tick) / p.rate_hz;
        const double* pose = t < o.flat ? flat.data() : t < o.flat + fist_seconds ? fist.data()
                                                      : take.frame_angles(static_cast<std::size_t>(tick - static_cast<std::uint64_t>(std::llround((o.flat + fist_seconds) * p.rate_hz))) % take.frames);
        if (o.garbage_every && tick > 0 && tick % o.garbage_every == 0) {
            auto bad = encode_messages(c, sim.sample(pose, t), tick, t).front();
            switch (garbage++ % 3) {
            case 0:                                                                            // short or cut
                if (c.kind == "opengloves") bad.resize(static_cast<std::size_t>(std::find(bad.begin(), bad.end(), '(') - bad.begin()) + 2);  // inside a key
                else bad.resize(bad.size() / 2);
                break;
            case 1:
                if (lines) bad.assign({'#', 0x13, 0x88, '~'});                                // noise
                else bad[0] = static_cast<std::uint8_t>(bad[0] ^ 0x80);                        // wrong id
                break;
            default: {                                                                         // a value broken
                glove_sample s = sim.sample(pose, t);
                if (!s.imu.empty()) s.imu[1] = {0, 0, 0, 0};
                else if (c.kind != "opengloves") s.flex[0] = 1e9;
                bad = encode_messages(c, s, tick, t).front();
                if (c.kind == "opengloves") {
                    const std::string over = "A" + std::to_string(c.analog_max + 1);
                    bad.insert(bad.begin(), over.begin(), over.end());
                }
            }
            }
            w.write({bad, t + 0.5 / p.rate_hz, 0});
        }
        if (o.drop_every && tick > 0 && tick % o.drop_every == 0) {
            ++dropped;
            continue;
        }
        for (auto& b : encode_messages(c, sim.sample(pose, t), tick, t)) w.write({std::move(b), t, 0}), ++written;
    }
    w.flush();
    std::printf("glove simulate: %s (%s, %s) -> %s: %zu reports at %g Hz (%.1f s flat%s, then %.1f s of motion), %zu dropped, %zu garbage\n",
                p.name.c_str(), o.motion.c_str(), o.emotion.c_str(), o.out.c_str(), written, p.rate_hz, o.flat,
                fist_seconds > 0 ? (", " + std::to_string(fist_seconds).substr(0, 3) + " s fist").c_str() : "", o.seconds, dropped, garbage);
}

inline void add_simulate(CLI::App* glove)
{
    auto* sub = glove->add_subcommand("simulate", "Write a raw report stream of a simulated glove performing a synthetic motion (for --replay)");
    auto o = std::make_shared<simulate_cli>();
    sub->add_option("--glove", o->src.glove, glove_help())->required();
    add_glove_settings(sub, o->src);
    sub->add_option("--out", o->out, "Raw stream file")->required();
    sub->add_option("--motion", o->motion, "Synthetic motion (crawling, gripping, patting, impatient, hand-on-mouse, pointing, pushing; and the extended set's waving, counting, scratching, piano, beckoning)")->capture_default_str();
    sub->add_option("--emotion", o->emotion, "Emotion of the synthetic take")->capture_default_str();
    sub->add_option("--seconds", o->seconds, "Seconds of motion")->capture_default_str();
    sub->add_option("--flat", o->flat, "Seconds of flat hand first (and as many of a fist for flex gloves)")->capture_default_str();
    sub->add_option("--drop-every", o->drop_every, "Lose every Nth report");
    sub->add_option("--garbage-every", o->garbage_every, "Insert a malformed report (short, wrong id, broken value) every N reports");
    sub->add_option("--seed", o->seed, "Seed of the synthetic take and the sensor mountings")->capture_default_str();
    sub->callback([o] { run_simulate(*o); });
}

}  // namespace handemo::cli::glove_cmd
