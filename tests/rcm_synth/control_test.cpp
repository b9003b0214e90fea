// A fitted model driving the synthesis (rcm/control.hpp): paths on the circumplex (parsing, sampling,
// titles, errors) and stylise_to_point() on a small synthetic hand set.
#include <handemo/motion.hpp>
#include <handemo/rcm.hpp>

#include <doctest/doctest.h>

#include <cmath>

using namespace handemo;
using doctest::Approx;

namespace {

std::vector<rcm::label_point> labels()
{
    return {{"sad", -0.725, -0.378}, {"neutral", 0.125, -0.388}, {"happy", 0.868, 0.263}};
}

std::string error_of(const std::function<void()>& f)
{
    try {
        f();
    } catch (const value_error& e) {
        return e.what();
    }
    return "(no error)";
}

}  // namespace

TEST_CASE("rcm path: labels and explicit points, every waypoint a sample")
{
    const auto w = rcm::parse_path("sad, neutral,happy", labels());
    REQUIRE(w.size() == 3);
    CHECK(w[1].name == "neutral");
    CHECK(w[1].valence == 0.125);
    CHECK(w[2].arousal == 0.263);
    CHECK(w[0].waypoint);

    const auto p = rcm::sample_path(w, 2);  // sad, midpoint, neutral, midpoint, happy
    REQUIRE(p.size() == 5);
    CHECK(p[0].name == "sad");
    CHECK(p[2].name == "neutral");
    CHECK(p[4].name == "happy");
    CHECK(!p[1].waypoint);
    CHECK(p[1].valence == Approx(-0.3));
    CHECK(p[1].arousal == Approx(-0.383));
    CHECK(p[3].valence == Approx((0.125 + 0.868) / 2));
    CHECK(rcm::sample_path(w, 1).size() == 3);
    CHECK(rcm::sample_path(w, 4).size() == 9);
    CHECK(rcm::sample_path({w[0]}, 3).size() == 1);  // one waypoint: one point

    const auto q = rcm::parse_path("-0.5:0.25,(0.6, -0.3),happy", labels());
    REQUIRE(q.size() == 3);
    CHECK(q[0].valence == -0.5);
    CHECK(q[0].arousal == 0.25);
    CHECK(q[1].valence == 0.6);
    CHECK(q[1].arousal == -0.3);
    CHECK(rcm::path_title(q[0]) == "(-0.50,0.25)");
    CHECK(rcm::path_title(q[1]) == "(0.60,-0.30)");
    CHECK(rcm::path_title(q[2]) == "happy");
    CHECK(rcm::path_title(rcm::sample_path(w, 2)[1]) == "(-0.30,-0.38)");
}

TEST_CASE("rcm path: bad waypoints are errors that name them")
{
    CHECK(error_of([] { rcm::parse_path("sad,ecstatic", labels()); }).find("waypoint 'ecstatic' is not a label with coordinates (known: sad, neutral, happy)") !=
          std::string::npos);
    CHECK(error_of([] { rcm::parse_path("0.5:1.5", labels()); }).find("1.5 is outside [-1, 1]") != std::string::npos);
    CHECK(error_of([] { rcm::parse_path("0.5:x", labels()); }).find("'x' is not a number") != std::string::npos);
    CHECK(error_of([] { rcm::parse_path("0.5:0.1:0.2", labels()); }).find("is not two numbers") != std::string::npos);
    CHECK(error_of([] { rcm::parse_path("(0.5,0.1", labels()); }).find("'(' without ')'") != std::string::npos);
    CHECK(error_of([] { rcm::parse_path("sad,,happy", labels()); }).find("empty waypoint") != std::string::npos);
    CHECK(error_of([] { rcm::parse_path("(0.5)", labels()); }).find("is not two numbers") != std::string::npos);
    CHECK(error_of([] { rcm::sample_path({}, 2); }).find("no waypoints") != std::string::npos);
    CHECK(error_of([] { rcm::sample_path(rcm::parse_path("sad", labels()), 0); }).find("--steps") != std::string::npos);
}

TEST_CASE("stylise_to_point: moves a hand clip toward the point with the model's features")
{
    // a small model: the synthetic hand set, one take at 30 fps, 10 features, no pose clusters
    const auto data = synthesize_dataset(1, 5, 30.0);
    std::vector<rcm::training_clip> clips;
    for (const auto& it : data) clips.push_back({&it.c, std::string(to_string(it.emo)), std::string(to_string(it.motion)), it.file_stem});
    rcm::fit_options fo;
    fo.cluster = false;
    fo.selection.min_features = 10;
    const auto m = rcm::fit_model(clips, rcm::load_circumplex(HANDEMO_RCM_CIRCUMPLEX), "circumplex.json", fo);
    const clip* in = nullptr;
    for (const auto& it : data)
        if (it.file_stem == "hand_pointing_sad_0") in = &it.c;
    REQUIRE(in != nullptr);

    rcm::point_options po;
    po.iterations = 40;
    const auto r = rcm::stylise_to_point(m, *in, 0.8, 0.5, po);
    CHECK(r.targeted.size() + r.skipped.size() == m.selected.size());
    CHECK(!r.targeted.empty());
    CHECK(r.synth.fit.loss_final < r.synth.fit.loss_initial);
    CHECK_NOTHROW(r.synth.motion.validate("stylised"));
    CHECK(r.synth.motion.skel.same_topology(in->skel));
    // closer to the target on the circumplex than the input was (deterministic: no random numbers anywhere)
    const auto a0 = m.analyse(*in), a1 = m.analyse(r.synth.motion);
    CHECK(std::hypot(a1.valence - 0.8, a1.arousal - 0.5) < std::hypot(a0.valence - 0.8, a0.arousal - 0.5));
    // g4 as a frame rate keeps the frame count
    po.frame_rate = true;
    CHECK(rcm::stylise_to_point(m, *in, 0.8, 0.5, po).synth.motion.frames == in->frames);

    CHECK(error_of([&] { rcm::stylise_to_point(m, *in, 1.5, 0, po); }).find("must be in [-1, 1]") != std::string::npos);
    CHECK(error_of([&] { rcm::stylise_to_point(m, *in, 0, std::nan(""), po); }).find("must be in [-1, 1]") != std::string::npos);
}
