#include "rigs.hpp"

#include <handemo/motion.hpp>
#include <handemo/retarget.hpp>

#include <doctest/doctest.h>
#include <nlohmann/json.hpp>

#include <filesystem>

#include <cmath>
#include <cstring>
#include <random>
#include <string>

using namespace handemo;
using namespace handemo::retarget;
using handemo::test::make_rig;
using handemo::test::random_motion;
using handemo::test::rig_style;

namespace {

/// Largest distance between the joints (and End Sites) of two clips on one skeleton, over every frame.
double max_position_error(const clip& a, const clip& b)
{
    REQUIRE(a.frames == b.frames);
    double e = 0;
    for (std::size_t f = 0; f < a.frames; ++f) {
        const auto pa = forward_kinematics(a.skel, a.frame_angles(f), a.frame_positions(f));
        const auto pb = forward_kinematics(b.skel, b.frame_angles(f), b.frame_positions(f));
        for (std::size_t j = 0; j < pa.joints.size(); ++j) {
            e = std::max(e, norm(sub(pa.joints[j], pb.joints[j])));
            e = std::max(e, norm(sub(pa.end_sites[j], pb.end_sites[j])));
        }
    }
    return e;
}

/// Shortest bone (joint to parent, at rest) of a skeleton: the scale the round-trip tolerance is relative to.
double shortest_bone(const skeleton& s)
{
    double m = 1e300;
    for (const auto& j : s.joints)
        if (j.parent >= 0 && norm(j.offset) > 0) m = std::min(m, norm(j.offset));
    return m;
}

void check_round_trip(const skeleton& src, const skeleton& dst, const map_options& o = {}, unsigned seed = 1)
{
    const auto m = make_map(src, dst, o);
    const clip in = random_motion(src, 40, seed);
    const clip there = retarget_clip(in, m);
    const clip back = write_back(in, there, m);
    const double err = max_position_error(in, back), tol = 1e-6 * shortest_bone(src);
    INFO(src.name << " -> " << dst.name << " (" << m.source_slots.convention << " -> " << m.target_slots.convention << ", " << m.pairs.size()
                  << " pairs): error " << err << ", tolerance " << tol);
    CHECK(err <= tol);
}

}  // namespace

TEST_CASE("euler_from_matrix inverts local_rotation in all six channel orders, nearest the reference")
{
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-179, 179);
    const std::array<axis, 3> orders[] = {{axis::x, axis::y, axis::z}, {axis::x, axis::z, axis::y}, {axis::y, axis::x, axis::z},
                                          {axis::y, axis::z, axis::x}, {axis::z, axis::x, axis::y}, {axis::z, axis::y, axis::x}};
    for (const auto& o : orders) {
        joint j;
        j.channels = {static_cast<channel>(3 + static_cast<int>(o[0])), static_cast<channel>(3 + static_cast<int>(o[1])),
                      static_cast<channel>(3 + static_cast<int>(o[2]))};
        for (int t = 0; t < 200; ++t) {
            const double a[3] = {u(rng), u(rng) / 2.2, u(rng)};
            const mat3 r = local_rotation(j, a);
            const vec3 e = euler_from_matrix(r, j.rotation_order(), {a[0] + 3, a[1] - 2, a[2] + 1});
            const mat3 r2 = local_rotation(j, e.data());
            for (int k = 0; k < 9; ++k) CHECK(std::abs(r[k] - r2[k]) < 1e-12);
            // the reference is near the generating angles, so those come back (up to rounding)
            for (int k = 0; k < 3; ++k) CHECK(std::abs(e[k] - a[k]) < 1e-7);
        }
        // the other solution and 360-degree multiples are chosen when the reference is near them
        const double a[3] = {30, 20, -40};
        const vec3 e = euler_from_matrix(local_rotation(j, a), j.rotation_order(), {a[0] + 360, a[1], a[2] - 720});
        CHECK(std::abs(e[0] - 390) < 1e-9);
        CHECK(std::abs(e[2] + 760) < 1e-9);
        // gimbal lock: the product is still exact
        double g[3] = {10, 20, 30};
        g[static_cast<int>(o[1])] = 90;
        const mat3 rg = local_rotation(j, g);
        const vec3 eg = euler_from_matrix(rg, j.rotation_order(), {0, 0, 0});
        const mat3 rg2 = local_rotation(j, eg.data());
        for (int k = 0; k < 9; ++k) CHECK(std::abs(rg[k] - rg2[k]) < 1e-9);
    }
}

TEST_CASE("conventions are detected from the joint names")
{
    using namespace handemo::test;
    CHECK(detect(hand_skeleton()).convention == "handemo-hand");
    CHECK(detect(make_rig(mixamo_names(), {})).convention == "cmu/mixamo");
    CHECK(detect(make_rig(mixamo_names(true, ""), {})).convention == "cmu/mixamo");
    CHECK(detect(make_rig(cmu_names(), {})).convention == "cmu/mixamo");
    CHECK(detect(make_rig(smplx_names(), {})).convention == "smpl");
    CHECK(detect(make_rig(unreal_names(), {})).convention == "unreal");
    CHECK(detect(make_rig(bandai_names(), {})).convention == "bandai");
    CHECK(detect(make_rig(openxr_names('r', true), {})).convention == "openxr");
    CHECK(detect(make_rig(openxr_names('r', false), {})).convention == "openxr");
    // CMU's spine is LowerBack, Mixamo's Spine; the chest is the highest spine joint
    const auto cmu = make_rig(cmu_names(), {});
    const auto b = detect(cmu);
    CHECK(cmu.joints[b.at("spine")].name == "LowerBack");
    CHECK(cmu.joints[b.at("chest")].name == "Spine1");
    const auto mx = make_rig(mixamo_names(), {});
    CHECK(mx.joints[detect(mx).at("chest")].name == "mixamorig:Spine2");
    // sides of OpenXR names from a prefix; none: the default side
    const auto xl = make_rig(openxr_names('l', true, "Left_"), {});
    CHECK(detect(xl).has("l.index1"));
    CHECK(!detect(xl).has("r.index1"));
    CHECK(detect(make_rig(openxr_names('r', false), {}), 'l').has("l.index1"));
}

TEST_CASE("bodies: retarget there and back reproduces every world joint position, across conventions, rest poses, units and channel orders")
{
    using namespace handemo::test;
    const rig_style cm_t{.name = "cm-T"};
    const rig_style m_a{.units = 0.01, .arm_scale = 1.15, .a_pose_deg = 40, .order = {axis::x, axis::y, axis::z}, .name = "m-A"};
    const rig_style relaxed{.units = 1, .arm_scale = 0.9, .a_pose_deg = 70, .finger_curl_deg = 25, .order = {axis::y, axis::z, axis::x},
                            .end_sites = false, .name = "relaxed"};
    const std::vector<std::pair<std::string, rig_names>> conv = {{"mixamo", mixamo_names()}, {"cmu", cmu_names()},
                                                                 {"smplx", smplx_names()},   {"unreal", unreal_names()},
                                                                 {"bandai", bandai_names()}};
    unsigned seed = 1;
    for (const auto& [an, a] : conv)
        for (const auto& [bn, b] : conv) {
            auto sa = make_rig(a, cm_t), sb = make_rig(b, an == bn ? relaxed : m_a);
            sa.name = an + " " + sa.name;
            sb.name = bn + " " + sb.name;
            check_round_trip(sa, sb, {}, seed++);
        }
}

TEST_CASE("bodies: a T-pose and an A-pose rig of one body, in different conventions and channel orders, move to the same world positions")
{
    using namespace handemo::test;
    // same bone lengths and units, different rest poses: the retarget must not depend on the rest pose
    const auto src = make_rig(mixamo_names(false), rig_style{.name = "T"});
    const auto dst = make_rig(smplx_names(), rig_style{.a_pose_deg = 45, .order = {axis::x, axis::z, axis::y}, .name = "A"});
    const auto m = make_map(src, dst);
    CHECK(m.scale == doctest::Approx(1).epsilon(1e-12));
    clip in = random_motion(src, 30, 11);
    // the mid spine joint (no slot) and the fingers stay still, so every driven chain is rigid between driven joints
    for (std::size_t j = 0; j < src.size(); ++j)
        if (m.pair_of_source[j] < 0)
            for (std::size_t f = 0; f < in.frames; ++f)
                for (std::size_t c = 0; c < 3; ++c) in.angle(f, j, c) = 0;
    const clip out = retarget_clip(in, m);
    for (std::size_t f = 0; f < in.frames; ++f) {
        const auto ps = forward_kinematics(in.skel, in.frame_angles(f), in.frame_positions(f));
        const auto pt = forward_kinematics(out.skel, out.frame_angles(f), out.frame_positions(f));
        for (const auto& pr : m.pairs) {
            INFO("frame " << f << " slot " << pr.slot);
            CHECK(norm(sub(ps.joints[pr.source], pt.joints[pr.target])) < 1e-9);
        }
    }
}

TEST_CASE("hands: any hand convention onto handemo's hand model and back, a hand picked out of a body, mirrored left hands")
{
    using namespace handemo::test;
    const skeleton model = hand_skeleton();
    unsigned seed = 100;
    for (const auto& names : {openxr_names('r', true), openxr_names('r', false), openxr_names('r', true, "Right_")}) {
        auto s = make_rig(names, rig_style{.units = 0.01, .finger_curl_deg = 20, .order = {axis::x, axis::y, axis::z}, .name = "xr"});
        check_round_trip(s, model, {}, seed++);
    }
    // the same single hand named without a side, declared left: mirrored onto the right-hand model
    check_round_trip(make_rig(openxr_names('l', false), rig_style{.name = "xr-left"}), model, {.hand = 'l'}, seed++);
    for (const auto& names : {smplx_names(), mixamo_names(), unreal_names()}) {
        const auto body = make_rig(names, rig_style{.a_pose_deg = 30, .name = "body"});
        check_round_trip(body, model, {.hand = 'r'}, seed++);
        check_round_trip(body, model, {.hand = 'l'}, seed++);
        CHECK(make_map(body, model, {.hand = 'l'}).mirror);
        CHECK(!make_map(body, model, {.hand = 'r'}).mirror);
    }
    // and the model's hand onto a body's hand
    check_round_trip(model, make_rig(smplx_names(), rig_style{.name = "smplx"}), {.hand = 'r'}, seed++);
}

TEST_CASE("hands: a mirrored left hand moves the right-hand model as the mirror image of its motion")
{
    using namespace handemo::test;
    // the right hand of a body moves; the left hand makes the mirror-image motion (a reflection x -> -x: the
    // angles about y and z change sign); each, picked out, must give the model the same motion
    const auto body = make_rig(smplx_names(), rig_style{.order = {axis::z, axis::x, axis::y}, .name = "mirror"});
    const auto model = hand_skeleton();
    clip in = random_motion(body, 25, 5);
    const auto b = detect(body);
    for (const char* part : {"hand", "thumb1", "thumb2", "thumb3", "index1", "index2", "index3", "middle1", "middle2", "middle3", "ring1",
                             "ring2", "ring3", "pinky1", "pinky2", "pinky3"}) {
        const std::size_t r = b.at(std::string("r.") + part), l = b.at(std::string("l.") + part);
        for (std::size_t f = 0; f < in.frames; ++f) {
            in.angle(f, l, 0) = in.angle(f, r, 0);
            in.angle(f, l, 1) = -in.angle(f, r, 1);
            in.angle(f, l, 2) = -in.angle(f, r, 2);
        }
    }
    const clip right = retarget_clip(in, make_map(body, model, {.hand = 'r'}));
    const clip left = retarget_clip(in, make_map(body, model, {.hand = 'l'}));
    CHECK(max_position_error(right, left) < 1e-9);
}

TEST_CASE("write-back: the channels of joints that drive nothing are bit-identical, also after a tempo change")
{
    using namespace handemo::test;
    const auto body = make_rig(smplx_names(), rig_style{.name = "smplx"});
    const auto model = hand_skeleton();
    const auto m = make_map(body, model, {.hand = 'r'});
    const clip in = random_motion(body, 33, 3);
    clip t = retarget_clip(in, m);
    // a "transfer": bend every finger of the model a little more, and make it 1.5x longer
    for (std::size_t f = 0; f < t.frames; ++f)
        for (std::size_t j = 3; j < model.size(); ++j) t.angle(f, j, 0) += 10;
    const clip longer = resample(t, 50);
    const clip out = write_back(in, longer, m);
    const clip ref = resample(in, 50);
    REQUIRE(out.frames == 50);
    CHECK(out.fps == in.fps);
    std::size_t changed = 0;
    for (std::size_t j = 0; j < body.size(); ++j) {
        const bool driven = m.pair_of_source[j] >= 0;
        for (std::size_t f = 0; f < out.frames; ++f)
            for (std::size_t c = 0; c < 3; ++c) {
                CHECK(std::memcmp(&out.positions[(f * body.size() + j) * 3 + c], &ref.positions[(f * body.size() + j) * 3 + c], sizeof(double)) == 0);
                if (!driven) CHECK(std::memcmp(&out.angles[(f * body.size() + j) * 3 + c], &ref.angles[(f * body.size() + j) * 3 + c], sizeof(double)) == 0);
                else changed += out.angle(f, j, c) != ref.angle(f, j, c);
            }
    }
    CHECK(changed > 0);
    // the driven joints are exactly the right hand's: wrist and fingers, not the forearm
    for (std::size_t j = 0; j < body.size(); ++j) {
        const std::string& n = body.joints[j].name;
        const bool right_hand = n.rfind("right_", 0) == 0 && n != "right_elbow" && n != "right_shoulder" && n != "right_collar" && n != "right_hip" &&
                                n != "right_knee" && n != "right_ankle" && n != "right_foot";
        CHECK_MESSAGE((m.pair_of_source[j] >= 0) == right_hand, n);
    }
    // an unchanged model output gives back the input, to rounding
    const clip same = write_back(in, t.frames == in.frames ? retarget_clip(in, m) : t, m);
    CHECK(max_position_error(same, in) < 1e-9);
}

TEST_CASE("errors name the conventions tried, the hands found, the joint and the map entry")
{
    using namespace handemo::test;
    const auto model = hand_skeleton();
    const auto cmu = make_rig(cmu_names(), rig_style{.name = "walk.bvh"});
    // a body without fingers has no hand
    CHECK_THROWS_WITH_AS(make_map(cmu, model), doctest::Contains("no hand recognised (tried conventions handemo-hand, bandai, cmu/mixamo, smpl, openxr, unreal"),
                         value_error);
    CHECK_THROWS_WITH_AS(make_map(cmu, model), doctest::Contains("looked for a wrist with the index, middle and little-finger knuckles"), value_error);
    // nothing recognisable at all
    skeleton junk;
    junk.name = "junk.bvh";
    junk.joints = {joint{.name = "a", .parent = -1, .offset = {0, 0, 0}}, joint{.name = "b", .parent = 0, .offset = {0, 1, 0}}};
    CHECK_THROWS_WITH_AS(make_map(junk, model), doctest::Contains("source skeleton 'junk.bvh': no hand recognised"), value_error);
    CHECK_THROWS_WITH_AS(make_map(junk, make_rig(bandai_names(), {})), doctest::Contains("looked for hips, both thighs"), value_error);
    // two hands and no choice
    const auto smplx = make_rig(smplx_names(), rig_style{.name = "gesture.bvh"});
    CHECK_THROWS_WITH_AS(make_map(smplx, model), doctest::Contains("has two hands, left ('left_wrist' with 'left_index1'...) and right ('right_wrist'"),
                         value_error);
    // asking for a hand that is not there
    CHECK_THROWS_WITH_AS(make_map(make_rig(openxr_names('r', false, "right_"), {}), model, {.hand = 'l'}), doctest::Contains("has no left hand"),
                         value_error);
    // zero-length bone: a finger joint on top of the next one, no End Site, parent at the same place
    {
        auto s = make_rig(openxr_names('r', false), rig_style{.end_sites = false, .name = "zero.bvh"});
        const auto b = detect(s);
        s.joints[b.at("r.index3")].offset = {0, 0, 0};
        s.joints[b.at("r.index_tip")].offset = {0, 0, 0};
        CHECK_THROWS_WITH_AS(make_map(s, model), doctest::Contains("joint 'index_distal' (slot r.index3): zero-length bone"), value_error);
    }
    // a non-finite offset (a skeleton built in code; the BVH reader refuses them)
    {
        auto s = make_rig(openxr_names('r', false), rig_style{.name = "nan.bvh"});
        s.joints[3].offset[1] = std::nan("");
        CHECK_THROWS_WITH_AS(make_map(s, model), doctest::Contains("has a non-finite offset"), value_error);
    }
    // degenerate rest pose: the knuckles in one point
    {
        auto s = make_rig(openxr_names('r', false), rig_style{.name = "flat.bvh"});
        const auto b = detect(s);
        const auto rest = forward_kinematics(s, std::vector<double>(s.size() * 3, 0.0).data());
        const vec3 want = rest.joints[b.at("r.index1")];
        const std::size_t p = b.at("r.pinky1");
        const vec3 parent = rest.joints[static_cast<std::size_t>(s.joints[p].parent)];
        s.joints[p].offset = sub(want, parent);
        CHECK_THROWS_WITH_AS(make_map(s, model), doctest::Contains("degenerate rest pose: r.index1 and r.pinky1 coincide"), value_error);
    }
}

TEST_CASE("map files: a custom rig, and every bad entry named")
{
    using namespace handemo::test;
    // a rig with names no convention knows
    rig_names names = smplx_names();
    for (auto& [k, v] : names) v = "jnt_" + std::to_string(std::hash<std::string>{}(v) % 100000);
    const auto s = make_rig(names, rig_style{.name = "custom.bvh"});
    CHECK_THROWS_AS(make_map(s, hand_skeleton()), value_error);
    std::string json = "{\"joints\": {";
    bool first = true;
    for (const auto& [k, v] : names) {
        if (k.rfind("r.", 0) != 0) continue;
        json += std::string(first ? "" : ", ") + "\"" + k + "\": \"" + v + "\"";
        first = false;
    }
    json += "}}";
    const auto b = parse_map(json, s, "custom.json");
    check_round_trip(s, hand_skeleton(), {.source_slots = b});
    // map_to_json writes what parse_map reads
    CHECK(parse_map(map_to_json(b, s), s, "again.json").slots == b.slots);

    const std::string wrist = names.at("r.hand"), index = names.at("r.index1");
    CHECK_THROWS_WITH_AS(parse_map("{\"joints\": {\"r.wrist\": \"" + wrist + "\"}}", s, "m.json"),
                         doctest::Contains("map m.json: entry 'r.wrist': unknown slot"), value_error);
    CHECK_THROWS_WITH_AS(parse_map("{\"joints\": {\"r.hand\": \"nope\"}}", s, "m.json"),
                         doctest::Contains("entry 'r.hand': skeleton 'custom.bvh' has no joint 'nope'"), value_error);
    CHECK_THROWS_WITH_AS(parse_map("{\"joints\": {\"r.hand\": \"" + wrist + "\", \"r.palm\": \"" + wrist + "\"}}", s, "m.json"),
                         doctest::Contains("is already the joint of entry"), value_error);
    CHECK_THROWS_WITH_AS(parse_map("{\"joints\": {\"r.hand\": \"" + wrist + "\", \"r.hand\": \"" + index + "\"}}", s, "m.json"),
                         doctest::Contains("entry 'r.hand' is written twice"), format_error);
    CHECK_THROWS_WITH_AS(parse_map("{\"joints\": {\"r.hand\": 3}}", s, "m.json"), doctest::Contains("must be a string"), format_error);
    CHECK_THROWS_WITH_AS(parse_map("{\"joints\": [1]}", s, "m.json"), doctest::Contains("expected an object with a \"joints\" object"), format_error);
    CHECK_THROWS_WITH_AS(parse_map("{\"joints\": {", s, "m.json"), doctest::Contains("not valid JSON"), format_error);
    // a cycle: two chains crossed (the knuckle of the index finger named as the middle finger's and the reverse is
    // fine, but the index's second joint as its knuckle and the knuckle as its second joint turns the chain around)
    std::string crossed = json;
    const std::string i1 = names.at("r.index1"), i2 = names.at("r.index2");
    const auto swap_at = [&](const std::string& a, const std::string& bb) {
        const auto p = crossed.find("\"" + a + "\"");
        REQUIRE(p != std::string::npos);
        crossed.replace(p, a.size() + 2, "\"@@\"");
        const auto q = crossed.find("\"" + bb + "\"");
        crossed.replace(q, bb.size() + 2, "\"" + a + "\"");
        crossed.replace(crossed.find("\"@@\""), 4, "\"" + bb + "\"");
    };
    swap_at(i1, i2);
    const auto bc = parse_map(crossed, s, "crossed.json");
    CHECK_THROWS_WITH_AS(make_map(s, hand_skeleton(), {.source_slots = bc}), doctest::Contains("would turn a chain around (a cycle)"), value_error);
}

TEST_CASE("the example map file (examples/maps/custom_rig.json) describes a rig that moves onto the hand model and the body")
{
    using namespace handemo::test;
    const std::string text = read_file(std::filesystem::path(HANDEMO_SOURCE_DIR) / "examples" / "maps" / "custom_rig.json");
    const auto j = nlohmann::json::parse(text);
    rig_names names;
    for (const auto& [slot, name] : j.at("joints").items()) names[slot] = name.get<std::string>();
    const auto s = make_rig(names, rig_style{.a_pose_deg = 20, .name = "custom_rig.bvh"});
    CHECK(detect(s).slots.size() < 5);  // no built-in convention knows it
    const auto b = parse_map(text, s, "custom_rig.json");
    CHECK(b.slots.size() == names.size());
    check_round_trip(s, hand_skeleton(), {.source_slots = b}, 77);
    check_round_trip(s, body_skeleton(), {.source_slots = b}, 78);
}
