#include <doctest/doctest.h>
#include <handemo/metrics/compare.hpp>
#include <handemo/motion/synth.hpp>
#include <handemo/stargan.hpp>

#include "helpers.hpp"

#include <cstring>
#include <filesystem>
#include <limits>
#include <memory>
#include <set>

#include <stdlib.h>

namespace fs = std::filesystem;
using namespace handemo;
using namespace handemo::stargan;
using namespace handemo::test;

namespace {

template <class M>
std::vector<float> params_of(M& m)
{
    std::vector<float> v;
    m.for_each_parameter([&](std::string_view, std::span<float> val, std::span<float>, std::span<const std::size_t>) {
        v.insert(v.end(), val.begin(), val.end());
    });
    return v;
}

}  // namespace

TEST_CASE("prepare_data: keyframes, Eq. 3 range, labels, padding, tempo")
{
    const auto clips = toy_set();
    REQUIRE(clips.size() == 15);
    const auto p = prepare_data<hand_tiny>(clips, tiny_info());
    CHECK(p.size() == 15);
    CHECK(p.H == 12);
    CHECK(p.W == 24);
    CHECK(p.range.p_min < p.range.p_max);
    // padding rows/columns are zero, the image part is in [-1, 1]
    for (std::size_t m = 0; m < p.size(); ++m)
        for (std::size_t c = 0; c < 3; ++c)
            for (std::size_t i = 0; i < 12; ++i)
                for (std::size_t j = 0; j < 24; ++j) {
                    const float v = p.images[((m * 3 + c) * 12 + i) * 24 + j];
                    if (i >= 9 || j >= 23)
                        CHECK(v == 0.0f);
                    else
                        CHECK((v >= -1.0f && v <= 1.0f));
                }
    // Table 1: angry is fast, sad is slow (tempo = duration ratio to neutral)
    CHECK(p.tempo[domain_index(tiny_info(), "angry")] < 1.0);
    CHECK(p.tempo[domain_index(tiny_info(), "sad")] > 1.0);
    CHECK(p.tempo[domain_index(tiny_info(), "neutral")] == 1.0);
    // a clip of another skeleton is refused
    auto bad = clips;
    bad[0].motion = clip::make(skeleton{"two", {joint{"a"}, joint{"b", 0}}}, 10, 30);
    CHECK_THROWS_AS(prepare_data<hand_tiny>(bad, tiny_info()), shape_error);
    auto unknown = clips;
    unknown[0].emotion = "bored";
    CHECK_THROWS_WITH_AS(prepare_data<hand_tiny>(unknown, tiny_info()), doctest::Contains("bored"), value_error);
}

TEST_CASE("a tiny StarGAN learns: D's classification loss falls on a toy set")
{
    // one motion type (gripping) x 5 emotions x 3 takes: the emotion is the only thing that varies
    std::vector<labelled_clip> clips;
    for (auto& it : synthesize_dataset(3, 7)) {
        if (it.motion != hand_motion::gripping) continue;
        const auto n = parse_clip_name(it.file_stem);
        clips.push_back({it.file_stem + ".bvh", n.content, n.emotion, n.take, it.c});
    }
    REQUIRE(clips.size() == 15);
    auto o = quiet(150);
    o.d_lr = o.g_lr = 1e-3;  // a tiny net and few steps: a larger step size than StarGAN's 1e-4
    trainer<hand_tiny> tr(tiny_info(), prepare_data<hand_tiny>(clips, tiny_info()), o);
    for (int i = 0; i < 150; ++i) tr.train_step();
    const auto& log = tr.log();
    REQUIRE(log.size() == 150);
    auto mean_cls = [&](std::size_t from, std::size_t to) {
        double s = 0;
        for (std::size_t i = from; i < to; ++i) s += log[i].values[2];
        return s / double(to - from);
    };
    const double first = mean_cls(0, 20), last = mean_cls(130, 150);
    MESSAGE("D/cls first 20 steps " << first << ", last 20 " << last);
    CHECK(first > 1.3);  // ~ln 5 at the start
    CHECK(last < 0.5 * first);
    double acc = 0;
    for (std::size_t i = 130; i < 150; ++i) acc += log[i].values[5] / 20;
    MESSAGE("D accuracy on real batches, last 20 steps: " << acc);
    CHECK(acc > 0.8);
    for (const auto& r : log)
        for (double v : r.values) CHECK(std::isfinite(v));
}

namespace {
/// 24 random images of configuration Cfg with labels cycling over its domains (8 contents), tempo and amplitude 1.
template <class Cfg>
prepared_data random_images_data(unsigned seed)
{
    using tr_t = trainer<Cfg>;
    prepared_data data;
    data.H = tr_t::H, data.W = tr_t::W, data.K = Cfg::keyframes, data.J = Cfg::joints, data.domains = Cfg::domains;
    std::mt19937 r(seed);
    std::uniform_real_distribution<float> u(-1, 1);
    constexpr std::size_t count = 24;
    data.images.resize(count * 3 * tr_t::H * tr_t::W);
    for (auto& v : data.images) v = u(r);
    for (std::size_t m = 0; m < count; ++m) {
        data.labels.push_back(int(m % Cfg::domains));
        data.contents.push_back("c" + std::to_string(m / Cfg::domains));
        data.sources.push_back("random" + std::to_string(m));
    }
    data.tempo.assign(Cfg::domains, 1.0);
    data.amplitude.assign(Cfg::domains, 1.0);
    return data;
}
}  // namespace

TEST_CASE("training with the tapes' panel cache gives the bits of packing at every convolution (1 and 2 shards)")
{
    // hand-embedded's layers take the weight-stationary kernel (the tiny config's channels fill no vector), so G's
    // and D's panels are packed: once per phase with the cache, G's kept from the D phase for the G phase
    using cfg = hand_embedded;
    using tr_t = trainer<cfg>;
    const prepared_data data = random_images_data<cfg>(3);
    const auto info = make_info<cfg>("hand-embedded", hand_domains(), "neutral");
    for (const std::size_t shards : {1, 2}) {
        CAPTURE(shards);
        auto o = quiet(3);
        o.n_critic = 1;  // a G phase at every step, after its D phase
        o.threads = 1;
        o.shards = shards;
        auto run = [&](bool cache) {
            auto tr = std::make_unique<tr_t>(info, data, o);
            tr->set_panel_cache(cache);
            for (int i = 0; i < 3; ++i) tr->train_step();
            return tr;
        };
        const auto cached = run(true), plain = run(false);
        CHECK(params_of(cached->gen()) == params_of(plain->gen()));
        CHECK(params_of(cached->disc()) == params_of(plain->disc()));
        REQUIRE(cached->log().size() == plain->log().size());
        for (std::size_t k = 0; k < cached->log().size(); ++k) CHECK(cached->log()[k].values == plain->log()[k].values);
    }
}

TEST_CASE("data-parallel training: two shards give the same bits on 1 and 2 threads; one shard within rounding")
{
    // batch 16 = 2 shards of 8: on one thread they run one after the other into their own gradient
    // buffers, on two at once, and the sums are the same. On four, each shard's convolutions split over 2 threads
    // again (the next test: the same bits); one shard sums the whole batch's gradients in another order.
    static_assert(trainer<hand_tiny>::max_shards() == 2);
    const auto clips = toy_set();
    auto o = quiet(6);
    o.n_critic = 2;
    o.residual = true;
    o.lambda_id = 1;
    o.lambda_pair = 1;
    o.lambda_delta = 0.5;
    o.ema = 0.9;
    o.augment = 0.05;
    const auto data = prepare_data<hand_tiny>(clips, tiny_info(), o);
    auto run = [&](unsigned threads, std::size_t shards, int steps) {
        auto oo = o;
        oo.threads = threads;
        oo.shards = shards;
        auto tr = std::make_unique<trainer<hand_tiny>>(tiny_info(), data, oo);
        for (int i = 0; i < steps; ++i) tr->train_step();
        return tr;
    };
    const auto one = run(1, 2, 6), two = run(2, 2, 6);
    CHECK(one->shards() == 2);
    CHECK(params_of(two->gen()) == params_of(one->gen()));
    CHECK(params_of(two->disc()) == params_of(one->disc()));
    CHECK(params_of(two->inference_gen()) == params_of(one->inference_gen()));
    REQUIRE(two->log().size() == one->log().size());
    for (std::size_t r = 0; r < one->log().size(); ++r) CHECK(two->log()[r].values == one->log()[r].values);
    // every loss term of the options above was computed (not left at 0) and is finite
    const auto& last = one->log().back().values;
    for (std::size_t k : {0, 1, 2, 3, 6, 7, 8, 11, 12, 13}) {
        CHECK(std::isfinite(last[k]));
        CHECK(last[k] != 0.0);
    }
    // the default: one shard on one thread (the trainer of earlier versions, bit for bit), two on more
    CHECK(run(1, 0, 0)->shards() == 1);
    CHECK(run(2, 0, 0)->shards() == 2);
    // four threads, and one shard: after two steps (before rounding differences grow through the updates)
    // the same losses and weights to float rounding, and bitwise repeatable (four threads: the bits of two,
    // "training's bits do not depend on its thread count")
    const auto two2 = run(2, 2, 2);
    const auto four = run(4, 2, 2), four_again = run(4, 2, 2), whole = run(2, 1, 2);
    CHECK(params_of(four->gen()) == params_of(four_again->gen()));
    CHECK(params_of(two2->gen()) != params_of(run(2, 2, 1)->gen()));  // G was updated in step 2
    for (const auto* t : {four.get(), whole.get()}) {
        auto* tt = const_cast<trainer<hand_tiny>*>(t);
        const auto a = params_of(tt->gen()), b = params_of(two2->gen());
        REQUIRE(a.size() == b.size());
        double diff = 0;
        for (std::size_t i = 0; i < a.size(); ++i) diff = std::max(diff, double(std::abs(a[i] - b[i])));
        CHECK(diff < 1e-5);  // Adam moves a weight by about the learning rate, 1e-4, in a step
        for (std::size_t k = 0; k < 10; ++k)
            CHECK(t->log().back().values[k] == doctest::Approx(two2->log().back().values[k]).epsilon(1e-4));
    }
    auto bad = o;
    bad.shards = 3;
    CHECK_THROWS_WITH_AS(trainer<hand_tiny>(tiny_info(), data, bad), doctest::Contains("shards 3"), value_error);
}

TEST_CASE("training's bits do not depend on its thread count for a given number of shards")
{
    // The weight gradients are split over a tape's threads by output channels, never by samples
    // (kernels::conv2d_backward_weight_parts()), and the rest of a step is split by samples, whose results do not
    // depend on the split: one shard on 1, 2 and 3 threads, and two shards on 2 and 4, train the same bits.
    // hand-embedded's layers are wide enough to be cut (the tiny configuration's are not).
    using cfg = hand_embedded;
    using tr_t = trainer<cfg>;
    const prepared_data data = random_images_data<cfg>(7);
    const auto info = make_info<cfg>("hand-embedded", hand_domains(), "neutral");
    auto run = [&](unsigned threads, std::size_t shards) {
        auto o = quiet(2);
        o.n_critic = 1;  // a G phase at every step
        o.threads = threads;
        o.shards = shards;
        auto tr = std::make_unique<tr_t>(info, data, o);
        for (int i = 0; i < 2; ++i) tr->train_step();
        return tr;
    };
    const auto one = run(1, 1);
    REQUIRE(one->shards() == 1);
    for (const unsigned threads : {2u, 3u}) {
        CAPTURE(threads);
        const auto more = run(threads, 1);
        CHECK(params_of(more->gen()) == params_of(one->gen()));
        CHECK(params_of(more->disc()) == params_of(one->disc()));
        REQUIRE(more->log().size() == one->log().size());
        for (std::size_t k = 0; k < one->log().size(); ++k) CHECK(more->log()[k].values == one->log()[k].values);
    }
    const auto two = run(2, 2), four = run(4, 2);
    CHECK(params_of(four->gen()) == params_of(two->gen()));
    CHECK(params_of(four->disc()) == params_of(two->disc()));
    CHECK(params_of(two->gen()) != params_of(one->gen()));  // two shards add their halves' gradients in another order
}

TEST_CASE("checkpoint round trip, bitwise resume, corrupted checkpoints refused")
{
    const auto clips = toy_set();
    const auto data = prepare_data<hand_tiny>(clips, tiny_info());
    const fs::path a = fresh_dir("handemo_train_a"), b = fresh_dir("handemo_train_b");
    {
        trainer<hand_tiny> full(tiny_info(), data, quiet(20));
        full.run(a);
        auto o = quiet(20);
        o.stop_at = 10;
        trainer<hand_tiny> first(tiny_info(), data, o);
        first.run(b);
        CHECK(first.step() == 10);
        trainer<hand_tiny> second(tiny_info(), data, quiet(20));
        second.run(b, /*resume=*/true);
        CHECK(second.step() == 20);
        CHECK(params_of(second.gen()) == params_of(full.gen()));
        CHECK(params_of(second.disc()) == params_of(full.disc()));
        CHECK(second.log().size() == full.log().size());
        // load() restores exactly what save() wrote
        trainer<hand_tiny> loaded(tiny_info(), data, quiet(20));
        loaded.load(a / "checkpoint.safetensors");
        CHECK(loaded.step() == 20);
        CHECK(params_of(loaded.gen()) == params_of(full.gen()));
    }
    CHECK(fs::exists(a / "generator.safetensors"));
    CHECK(fs::exists(a / "log.csv"));
    CHECK(fs::exists(a / "range.json"));

    // a flipped byte in the data section: checksum mismatch
    std::string bytes = read_file(a / "checkpoint.safetensors");
    const fs::path bad = fresh_dir("handemo_train_bad");
    fs::create_directories(bad);
    std::string flipped = bytes;
    flipped[flipped.size() - 100] ^= 0x5a;
    write_file_atomic(bad / "checkpoint.safetensors", flipped);
    CHECK_THROWS_WITH_AS(read_checkpoint(bad / "checkpoint.safetensors"), doctest::Contains("checksum"), format_error);
    CHECK_THROWS_AS(load_model(bad), format_error);
    // truncated
    write_file_atomic(bad / "checkpoint.safetensors", bytes.substr(0, bytes.size() / 2));
    CHECK_THROWS_AS(load_model(bad), format_error);
    // resuming from it is refused too, and a missing one is an io_error
    trainer<hand_tiny> t3(tiny_info(), data, quiet(20));
    CHECK_THROWS_AS(t3.run(bad, true), format_error);
    CHECK_THROWS_AS(t3.run(fresh_dir("handemo_train_none"), true), io_error);
}

TEST_CASE("a NaN loss stops training naming the step and term, and keeps the last good checkpoint")
{
    const auto clips = toy_set();
    auto data = prepare_data<hand_tiny>(clips, tiny_info());
    const fs::path d = fresh_dir("handemo_train_nan");
    {
        trainer<hand_tiny> ok(tiny_info(), data, quiet(10));
        ok.run(d);
    }
    const std::string before = read_file(d / "checkpoint.safetensors");
    for (std::size_t i = 0; i < data.images.size(); i += 97) data.images[i] = std::nanf("");
    trainer<hand_tiny> poisoned(tiny_info(), data, quiet(20));
    CHECK_THROWS_WITH_AS(poisoned.run(d, true), doctest::Contains("step 11: loss term D/real is NaN"), value_error);
    CHECK(read_file(d / "checkpoint.safetensors") == before);
}

TEST_CASE("residual G (handemo preset) is exactly the identity at initialisation, through the whole transfer")
{
    auto clips = toy_set();
    const fs::path d = fresh_dir("handemo_train_residual_init");
    auto o = handemo_options();
    o.iters = 10;
    o.threads = 1;
    o.progress_out = nullptr;
    o.gate_centre = false;  // a trainer on its own fits no gate and computes no centre (train_model() does both)
    const auto data = prepare_data<hand_tiny>(clips, tiny_info(), o);
    CHECK(data.range.per_channel());
    trainer<hand_tiny> tr(tiny_info(), data, o);
    // G(x, c) == x for every training image and target before any step
    auto& g = tr.inference_gen();
    CHECK(g.residual());
    typename generator<float, with_batch<hand_tiny, 1>>::workspace ws;
    generator<float, with_batch<hand_tiny, 1>> g1;
    g1.set_residual(true);
    zip_parameters(g, g1, [](std::span<const float> a, std::span<float> b) { std::copy(a.begin(), a.end(), b.begin()); });
    const std::size_t per = 3 * data.H * data.W;
    std::vector<float> label(5, 0.f), out(per);
    label[0] = 1.f;
    for (std::size_t m = 0; m < data.size(); ++m) {
        g1.infer(data.images.data() + m * per, label.data(), out.data(), ws);
        REQUIRE(std::memcmp(out.data(), data.images.data() + m * per, per * sizeof(float)) == 0);
    }
    tr.save(d);
    const auto model = load_model(d);
    CHECK(model->residual());
    const clip& in = clips[2].motion;
    const auto kin = extract_keyframes<dynamic_keyframes>(in, 9);
    for (const char* e : {"neutral", "angry"}) {
        const auto r = model->transfer(in, e);
        // the output is the spline through the input's own keyframes (times the learned amplitude about each
        // channel's anchor, within the hand's joint limits): no Eq. 3 quantisation or clamping reaches a residual
        // model's output
        auto k = kin;
        scale_keyframe_excursions(k, r.amplitude, r.amplitude_anchor);
        model->clamp_to_limits(k);
        clip expect = reconstruct(k, in.skel, r.motion.frames, in.fps);
        model->clamp_to_limits(expect);
        double worst = 0;
        for (std::size_t i = 0; i < expect.angles.size(); ++i) worst = std::max(worst, std::abs(expect.angles[i] - r.motion.angles[i]));
        CHECK(worst < 1e-9);
    }
    CHECK(model->transfer(in, "angry").amplitude > 1.0);  // Table 1: angry is larger
}

TEST_CASE("prepare_data: the paired-target table pairs every image with its content and take in each emotion")
{
    const auto clips = toy_set();
    const auto p = prepare_data<hand_tiny>(clips, tiny_info());
    REQUIRE(p.partner.size() == clips.size() * 5);
    for (std::size_t m = 0; m < clips.size(); ++m) {
        CHECK(p.partner[m * 5 + static_cast<std::size_t>(p.labels[m])] == static_cast<int>(m));
        for (std::size_t d = 0; d < 5; ++d) {
            const int q = p.partner[m * 5 + d];
            REQUIRE(q >= 0);
            CHECK(clips[static_cast<std::size_t>(q)].content == clips[m].content);
            CHECK(clips[static_cast<std::size_t>(q)].take == clips[m].take);
            CHECK(p.labels[static_cast<std::size_t>(q)] == static_cast<int>(d));
        }
    }
}

TEST_CASE("EMA weights: saved beside G, used by transfer, resumed bitwise")
{
    const auto clips = toy_set();
    auto o = handemo_options();
    o.iters = 20;
    o.threads = 1;
    o.progress_out = nullptr;
    o.log_every = 1;
    o.checkpoint_every = 10;
    const fs::path a = fresh_dir("handemo_ema_a"), b = fresh_dir("handemo_ema_b");
    const auto data = prepare_data<hand_tiny>(clips, tiny_info(), o);
    trainer<hand_tiny> full(tiny_info(), data, o);
    full.run(a);
    CHECK(params_of(full.inference_gen()) != params_of(full.gen()));  // the average lags G
    auto o2 = o;
    o2.stop_at = 10;
    {
        trainer<hand_tiny> half(tiny_info(), data, o2);
        half.run(b);
    }
    trainer<hand_tiny> resumed(tiny_info(), data, o);
    resumed.run(b, true);
    CHECK(params_of(resumed.inference_gen()) == params_of(full.inference_gen()));
    CHECK(params_of(resumed.gen()) == params_of(full.gen()));
    const auto f = read_safetensors(a / "checkpoint.safetensors");
    CHECK(f.find("G_ema.main.0.weight") != nullptr);
    // the generator file (PyTorch names) holds the EMA weights
    const auto gen = read_safetensors(a / "generator.safetensors");
    const auto w = gen.get<float>("main.0.weight");
    std::vector<float> ema0;
    full.inference_gen().for_each_parameter([&](std::string_view n, std::span<float> v, std::span<float>, auto) {
        if (n == "main.0.weight") ema0.assign(v.begin(), v.end());
    });
    CHECK(w == ema0);
}

TEST_CASE("end to end: where emotions are large offsets, transfer of an unseen content beats identity")
{
    // a toy set whose emotions add large per-emotion offsets to the neutral take: 4 contents, one held out
    std::vector<labelled_clip> all;
    const auto emos = hand_domains();
    for (auto& it : synthesize_dataset(1, 3)) {
        if (it.emo != emotion::neutral) continue;
        if (it.motion == hand_motion::pushing || it.motion == hand_motion::hand_on_mouse || it.motion == hand_motion::impatient)
            continue;
        for (std::size_t e = 0; e < emos.size(); ++e) {
            labelled_clip c;
            c.content = std::string(to_string(it.motion));
            c.emotion = emos[e];
            c.take = "0";
            c.path = "toy_" + c.content + "_" + c.emotion + "_0.bvh";
            c.motion = it.c;
            if (emos[e] != "neutral")
                for (std::size_t f = 0; f < c.motion.frames; ++f)
                    for (std::size_t j = 1; j < 23; ++j) c.motion.angle(f, j, 0) += 12.0 * std::sin(double(e * 7 + j));
            all.push_back(std::move(c));
        }
    }
    std::vector<labelled_clip> train, held;
    for (auto& c : all) (c.content == "gripping" ? held : train).push_back(c);
    auto o = handemo_options();
    o.iters = 600;
    o.threads = 2;
    o.progress_out = nullptr;
    o.checkpoint_every = 10000;
    o.gate_centre = false;  // a trainer on its own fits no gate and computes no centre (train_model() does both)
    const fs::path d = fresh_dir("handemo_e2e_offsets");
    trainer<hand_tiny> tr(tiny_info(), prepare_data<hand_tiny>(train, tiny_info(), o), o);
    tr.run(d);
    const auto model = load_model(d);
    const labelled_clip* in = nullptr;
    for (const auto& c : held)
        if (c.emotion == "neutral") in = &c;
    REQUIRE(in);
    double s_model = 0, s_identity = 0;
    for (const auto& c : held) {
        if (c.emotion == "neutral") continue;
        const auto out = model->transfer(in->motion, c.emotion);
        const auto real = extract_keyframes<9>(c.motion);
        s_model += metrics::keyframe_rmse(extract_keyframes<9>(out.motion), real);
        s_identity += metrics::keyframe_rmse(extract_keyframes<9>(in->motion), real);
    }
    MESSAGE("held-out content: transfer RMSE " << s_model / 4 << " deg, identity " << s_identity / 4 << " deg");
    CHECK(s_model < 0.85 * s_identity);
}

TEST_CASE("end to end: G learns an emotion effect that depends on the content, which statistics() cannot express")
{
    // 7 motion types x 2 takes of the synthetic hand set, neutral only; each emotion is its neutral take shifted
    // in time by a quarter cycle (later for angry and happy, earlier for sad and fearful: one keyframe column, a
    // take being two cycles on 9 keyframes). A shift's change depends on the movement and averages to zero over
    // the clip, so the amplitude stage, the tempo and the posture prior (statistics()) can do nothing with it,
    // while G sees the movement. Trained on take 0, scored on take 1 (new takes of the trained movements).
    std::vector<labelled_clip> train, test;
    const auto emos = hand_domains();
    for (auto& it : synthesize_dataset(2, 3)) {
        if (it.emo != emotion::neutral) continue;
        for (const auto& e : emos) {
            labelled_clip c;
            c.content = std::string(to_string(it.motion)), c.emotion = e, c.take = std::to_string(it.take);
            c.path = "toy_" + c.content + "_" + c.emotion + "_" + c.take + ".bvh";
            c.motion = it.c;
            const std::size_t n = it.c.frames - 1, quarter = (n + 4) / 8;  // frame n repeats frame 0's phase
            const std::size_t shift = e == "neutral" ? 0 : (e == "angry" || e == "happy") ? n - quarter : quarter;
            for (std::size_t f = 0; f <= n; ++f)
                for (std::size_t j = 0; j < it.c.joint_count(); ++j)
                    for (std::size_t a = 0; a < 3; ++a) {
                        c.motion.angle(f, j, a) = it.c.angle((f + shift) % n, j, a);
                        if (!c.motion.positions.empty()) c.motion.position(f, j, a) = it.c.position((f + shift) % n, j, a);
                    }
            (it.take == 0 ? train : test).push_back(std::move(c));
        }
    }
    REQUIRE(train.size() == 35);
    REQUIRE(test.size() == 35);
    const auto info = make_info<hand_embedded>("hand-embedded", hand_domains(), "neutral");
    auto o = handemo_options();
    // a short run: 300 steps at 5x the preset's learning rate, an EMA over about the last 100 steps, and the paired
    // loss leading (lambda_pair 100): with the preset's 10, G's change follows D's domain classifier more than the
    // paired takes and does not beat statistics() at this length (5.7 deg against 5.2)
    o.iters = 300;
    o.g_lr = o.d_lr = 5e-4;
    o.ema = 0.99;
    o.lambda_pair = 100;
    o.threads = 2;
    o.gate_folds = 0;  // G's whole change
    o.progress_out = nullptr;
    o.checkpoint_every = 100000;
    const fs::path d = fresh_dir("handemo_e2e_content_effect");
    trainer<hand_embedded> tr(info, prepare_data<hand_embedded>(train, info, o), o);
    tr.run(d);
    const auto model = load_model(d);
    model->set_prior_posture(posture_prior<9>(train, info));
    double g = 0, stat = 0, id = 0;
    std::size_t pairs = 0, lower = 0;
    for (const auto& c : test) {
        if (c.emotion == "neutral") continue;
        const auto in = std::find_if(test.begin(), test.end(), [&](const labelled_clip& x) { return x.content == c.content && x.emotion == "neutral"; });
        REQUIRE(in != test.end());
        const auto real = extract_keyframes<9>(c.motion);
        const auto rmse = [&](const clip& out) { return metrics::keyframe_rmse(extract_keyframes<9>(out), real); };
        const double a = rmse(model->transfer(in->motion, c.emotion).motion), b = rmse(model->statistics(in->motion, c.emotion).motion);
        g += a, stat += b, id += rmse(in->motion), ++pairs, lower += a < b;
    }
    REQUIRE(pairs == 28);
    MESSAGE("new takes: G " << g / 28 << " deg, statistics " << stat / 28 << " deg, identity " << id / 28 << " deg; G lower in " << lower
                            << " of 28 pairs");
    CHECK(stat > 0.9 * id);  // statistics cannot express a shift
    CHECK(g < 0.8 * stat);
    CHECK(lower >= 20);  // at least 70% of the pairs
}

TEST_CASE("the checkpoint carries the detail layer; checkpoints without it load; add_detail keeps the keyframes")
{
    const auto clips = toy_set();
    const auto data = prepare_data<hand_tiny>(clips, tiny_info());
    REQUIRE(data.detail);
    CHECK(data.detail->channels == 23 * 3);
    const fs::path a = fresh_dir("handemo_train_detail");
    {
        trainer<hand_tiny> t(tiny_info(), data, quiet(4));
        t.run(a);
    }
    const auto info = read_checkpoint(a / "checkpoint.safetensors").second;
    REQUIRE(info.detail);
    CHECK(info.detail->emotions == data.detail->emotions);
    CHECK(info.detail->amplitude == data.detail->amplitude);
    const auto model = load_model(a);
    REQUIRE(model->has_detail());
    // the layer's own property, zero at the keyframes, without the hand's joint limits (whose clamp of the frames
    // next to a keyframe moves it where the detail passes a limit; limits_test.cpp has them)
    model->set_limits(std::vector<double>(23 * 3, -std::numeric_limits<double>::infinity()),
                      std::vector<double>(23 * 3, std::numeric_limits<double>::infinity()));
    const auto neutral = std::find_if(clips.begin(), clips.end(), [](const labelled_clip& c) { return c.emotion == "neutral"; });
    REQUIRE(neutral != clips.end());
    const clip& in = neutral->motion;
    const auto r = model->transfer(in, "sad");
    const clip d = model->add_detail(r.motion, in, "sad");
    CHECK(d.frames == r.motion.frames);
    const auto k0 = extract_keyframes<hand_tiny::keyframes>(r.motion), k1 = extract_keyframes<hand_tiny::keyframes>(d);
    double moved = 0, keymoved = 0;
    for (std::size_t i = 0; i < k0.angles.size(); ++i) keymoved = std::max(keymoved, std::abs(k0.angles[i] - k1.angles[i]));
    for (std::size_t i = 0; i < d.angles.size(); ++i) moved = std::max(moved, std::abs(d.angles[i] - r.motion.angles[i]));
    CHECK(keymoved < 1e-9);
    CHECK(moved > 1e-3);  // the toy clips have detail between their keyframes

    // a checkpoint written before the layer existed (no 'detail' field) still loads, and says it has none
    auto f = read_safetensors(a / "checkpoint.safetensors");
    auto meta = nlohmann::json::parse(f.metadata.at("handemo"));
    meta.erase("detail");
    f.metadata["handemo"] = meta.dump();
    f.metadata["checksum"] = handemo::stargan::detail::checkpoint_checksum(f);
    const fs::path old = fresh_dir("handemo_train_detail_old");
    fs::create_directories(old);
    write_safetensors(old / "checkpoint.safetensors", f);
    const auto old_model = load_model(old);
    CHECK_FALSE(old_model->has_detail());
    CHECK_THROWS_WITH_AS(old_model->add_detail(r.motion, in, "sad"), doctest::Contains("no detail layer"), value_error);
    // a detail layer for another skeleton is refused naming the field
    meta = nlohmann::json::parse(read_safetensors(a / "checkpoint.safetensors").metadata.at("handemo"));
    meta["detail"]["channels"] = 6;
    meta["detail"]["amplitude"] = nlohmann::json::array();
    for (std::size_t e = 0; e < info.detail->emotions.size(); ++e) meta["detail"]["amplitude"].push_back(std::vector<double>(6, 1.0));
    f.metadata["handemo"] = meta.dump();
    f.metadata["checksum"] = handemo::stargan::detail::checkpoint_checksum(f);
    write_safetensors(old / "checkpoint.safetensors", f);
    CHECK_THROWS_WITH_AS(read_checkpoint(old / "checkpoint.safetensors"), doctest::Contains("metadata 'detail' is for 2 joints"), format_error);
    // options of the wrong type are refused naming the field, not let through as a JSON type error
    for (const auto& [key, value] : {std::pair<std::string, nlohmann::json>{"amplitude", "yes"}, {"residual", 1}}) {
        meta = nlohmann::json::parse(read_safetensors(a / "checkpoint.safetensors").metadata.at("handemo"));
        meta["options"][key] = value;
        f.metadata["handemo"] = meta.dump();
        f.metadata["checksum"] = handemo::stargan::detail::checkpoint_checksum(f);
        write_safetensors(old / "checkpoint.safetensors", f);
        CHECK_THROWS_WITH_AS(read_checkpoint(old / "checkpoint.safetensors"), doctest::Contains(("metadata field 'options." + key + "'").c_str()), format_error);
    }
    // the training skeleton is stored, and a checkpoint whose stored skeleton disagrees with joint_names is refused
    CHECK(read_checkpoint(a / "checkpoint.safetensors").second.skel.has_value());
    f = read_safetensors(a / "checkpoint.safetensors");
    {
        skeleton other = hand_skeleton();
        other.joints[5].name = "renamed";
        f.metadata["skeleton"] = to_bvh_string(clip::make(other, 1, 30));
    }
    f.metadata["checksum"] = handemo::stargan::detail::checkpoint_checksum(f);
    write_safetensors(old / "checkpoint.safetensors", f);
    CHECK_THROWS_WITH_AS(read_checkpoint(old / "checkpoint.safetensors"), doctest::Contains("metadata 'skeleton' joint 5 is 'renamed'"), format_error);
}

TEST_CASE("resume names a checkpoint path whose status cannot be read (io_error, not std::filesystem::filesystem_error)")
{
    std::string t = (fs::temp_directory_path() / "handemo_resume_XXXXXX").string();
    REQUIRE(::mkdtemp(t.data()) != nullptr);
    const fs::path dir = t, ck = dir / "checkpoint.safetensors";
    fs::create_symlink(ck, ck);  // a link to itself: stat fails with ELOOP
    trainer<hand_tiny> tr(tiny_info(), prepare_data<hand_tiny>(toy_set(3), tiny_info()), quiet(1));
    CHECK_THROWS_WITH_AS(tr.run(dir, /*resume=*/true), doctest::Contains(ck.string().c_str()), io_error);
    CHECK_THROWS_WITH_AS(read_checkpoint(checkpoint_file(ck)), doctest::Contains(ck.string().c_str()), io_error);
    fs::remove_all(dir);
}

TEST_CASE("statistics(): every learned part but G is the transfer with G's change weighted 0 and the prior 1")
{
    auto clips = toy_set();
    const fs::path d = fresh_dir("handemo_train_statistics");
    auto o = handemo_options();
    o.iters = 3;
    o.threads = 1;
    o.progress_out = nullptr;
    o.gate_folds = 0;
    trainer<hand_tiny> tr(tiny_info(), prepare_data<hand_tiny>(clips, tiny_info(), o), o);
    tr.run(d);
    auto [f, info] = read_checkpoint(d / "checkpoint.safetensors");
    // every part away from its neutral value, so leaving one out (or applying it twice) shows
    info.amplitude = {1.3, 0.8, 0.9, 1.1, 1.2};
    info.tempo = {0.7, 1.2, 1.0, 1.6, 0.9};
    const auto model = load_model(f, info);
    REQUIRE(model->residual());
    REQUIRE(model->amplitude_stage());
    std::vector<std::vector<double>> prior(5, std::vector<double>(model->joints() * 3));
    for (std::size_t e = 0; e < prior.size(); ++e)
        for (std::size_t ch = 0; ch < prior[e].size(); ++ch) prior[e][ch] = 6.0 * std::sin(double(e * 31 + ch));
    model->set_prior_posture(prior);
    const clip& in = clips[2].motion;
    for (const char* source : {"neutral", "happy"})
        for (const char* target : {"angry", "sad", "fearful", "neutral"}) {
            CAPTURE(source);
            CAPTURE(target);
            const auto s = model->statistics(in, target, source);
            const auto p = model->parts(in, target, source);
            const clip expect = model->finish(in, p, 0, 0, 1);
            REQUIRE(s.motion.frames == expect.frames);
            CHECK(s.motion.frames == emotion_model::output_frames(in.frames, model->tempo(target, source)));
            CHECK(s.tempo == model->tempo(target, source));
            CHECK(s.amplitude == model->amplitude(target, source));
            CHECK(s.motion.angles == expect.angles);  // bit for bit: the same operations in the same order
            CHECK(s.motion.positions.size() == in.positions.size() / in.frames * s.motion.frames);
        }
    // a model without a prior: the amplitude stage and the tempo alone
    auto [f2, info2] = read_checkpoint(d / "checkpoint.safetensors");
    const auto plain = load_model(f2, info2);
    const auto s = plain->statistics(in, "angry");
    auto k = extract_keyframes<dynamic_keyframes>(in, 9);
    scale_keyframe_excursions(k, plain->amplitude("angry"), plain->info().amplitude_anchor);
    plain->clamp_to_limits(k);
    clip expect = reconstruct(k, in.skel, s.motion.frames, in.fps);
    plain->clamp_to_limits(expect);
    double worst = 0;
    for (std::size_t i = 0; i < expect.angles.size(); ++i) worst = std::max(worst, std::abs(expect.angles[i] - s.motion.angles[i]));
    CHECK(worst < 1e-9);
    CHECK_THROWS_AS(plain->statistics(in, "bored"), value_error);
}

TEST_CASE("neutral_share: the led slots take a neutral source and another domain, the rest keep StarGAN's sampling")
{
    CHECK(neutral_led_slots(0.0, 16) == 0);
    CHECK(neutral_led_slots(0.5, 16) == 8);
    CHECK(neutral_led_slots(0.3, 16) == 5);
    CHECK(neutral_led_slots(1.0, 16) == 16);
    for (std::size_t led : {0, 1, 5, 8, 16}) {
        std::size_t count = 0, first_half = 0;
        for (std::size_t n = 0; n < 16; ++n)
            if (neutral_led(n, led, 16)) ++count, first_half += n < 8;
        CHECK(count == led);
        CHECK(first_half == led / 2);  // spread: each half of the batch (a shard) takes its share
    }

    using cfg = with_batch<hand_tiny, 16>;
    const auto clips = toy_set();
    const auto data = prepare_data<cfg>(clips, tiny_info());
    REQUIRE(data.neutral == 2);  // hand_domains(): angry, happy, neutral, sad, fearful
    auto o = quiet(12);
    o.neutral_share = 0.5;
    trainer<cfg> tr(tiny_info(), data, o);
    trainer<cfg> plain(tiny_info(), data, quiet(12));
    std::size_t led_neutral = 0, led_other_target = 0, other_neutral = 0;
    for (int s = 0; s < 12; ++s) {
        tr.train_step();
        plain.train_step();
        std::multiset<int> src, trg;
        for (std::size_t n = 0; n < 16; ++n) {
            const int a = tr.batch_sources()[n], b = tr.batch_targets()[n];
            if (neutral_led(n, 8, 16)) {
                led_neutral += a == data.neutral;
                led_other_target += b != data.neutral && b >= 0 && b < 5;
            } else {
                src.insert(a), trg.insert(b);
                other_neutral += a == data.neutral;
            }
        }
        CHECK(src == trg);  // the other slots' targets: their own labels permuted
    }
    CHECK(led_neutral == 12 * 8);
    CHECK(led_other_target == 12 * 8);
    MESSAGE("neutral sources in the unled slots: " << other_neutral << " of " << 12 * 8);
    // share 0 is StarGAN's sampling, bit for bit what an option-less run trains
    auto z = quiet(3);
    z.neutral_share = 0.0;
    trainer<cfg> zero(tiny_info(), data, z), base(tiny_info(), data, quiet(3));
    for (int s = 0; s < 3; ++s) zero.train_step(), base.train_step();
    CHECK(params_of(zero.gen()) == params_of(base.gen()));
    CHECK(zero.batch_targets() == base.batch_targets());
    // the led run trains something else
    CHECK(params_of(tr.gen()) != params_of(plain.gen()));

    auto bad = quiet(1);
    bad.neutral_share = 1.5;
    CHECK_THROWS_WITH_AS(bad.validate(), doctest::Contains("neutral_share"), value_error);
    std::vector<labelled_clip> no_neutral;
    for (const auto& c : clips)
        if (c.emotion != "neutral") no_neutral.push_back(c);
    CHECK_THROWS_WITH_AS((trainer<cfg>(tiny_info(), prepare_data<cfg>(no_neutral, tiny_info()), o)),
                         doctest::Contains("needs neutral clips"), value_error);
}
