#include <handemo/motion/codec.hpp>

#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <random>

using namespace handemo;

namespace {
template <std::size_t K>
keyframes<K> random_keyframes(std::size_t j, std::size_t k, std::mt19937_64& g, double lo, double hi)
{
    auto r = keyframes<K>::make(j, k);
    for (auto& v : r.angles) v = lo + (hi - lo) * static_cast<double>(g() >> 11) * 0x1.0p-53;
    return r;
}

template <std::size_t K>
void check_roundtrip(std::size_t J, std::size_t k, std::uint64_t seed)
{
    std::mt19937_64 g(seed);
    std::vector<keyframes<K>> set;
    for (int s = 0; s < 5; ++s) set.push_back(random_keyframes<K>(J, k, g, -120.0 - s, 95.0 + 3 * s));
    const angle_range r = compute_range(set);
    CHECK(r.keyframes == k);
    CHECK(r.joints == J);
    const double bound = (r.p_max - r.p_min) / 510.0;
    CHECK(r.max_roundtrip_error() == doctest::Approx(bound));
    double worst = 0;
    for (const auto& kf : set) {
        const auto px = encode(kf, r);
        REQUIRE(px.values.size() == k * J * 3);
        CHECK(px.count() == k);
        const auto back = decode(px, r);
        for (std::size_t i = 0; i < kf.angles.size(); ++i) worst = std::max(worst, std::abs(back.angles[i] - kf.angles[i]));
        // Network range round trip is lossless on pixels.
        const auto net = to_network(px);
        for (float x : net.data) CHECK((x >= -1.0f && x <= 1.0f));
        CHECK(from_network(net).values == px.values);
    }
    MESSAGE(J << "x" << k << ": max round-trip error " << worst << " deg, bound " << bound);
    CHECK(worst <= bound * (1 + 1e-12));
    CHECK(worst > 0.5 * bound);  // random data really exercises the rounding
}
}  // namespace

TEST_CASE("codec: Eq. 3 / Eq. 6 round trip within (p_max - p_min) / 510 for any J and K")
{
    check_roundtrip<9>(23, 9, 1);
    check_roundtrip<9>(22, 9, 2);
    check_roundtrip<4>(5, 4, 3);
    check_roundtrip<dynamic_keyframes>(7, 13, 4);
}

TEST_CASE("codec: pixel layout, clamping and the network range")
{
    auto k = keyframes<2>::make(3);
    angle_range r{-90, 90, 0, 0};
    k.at(0, 0, 0) = -90;   // -> 0
    k.at(0, 0, 1) = 90;    // -> 255
    k.at(0, 0, 2) = 0;     // -> round(127.5) = 128
    k.at(1, 2, 1) = 500;   // clamped -> 255
    k.at(1, 2, 2) = -500;  // clamped -> 0
    k.at(1, 1, 0) = std::nan("");
    const auto px = encode(k, r);
    CHECK(px.at(0, 0, 0) == 0);
    CHECK(px.at(0, 0, 1) == 255);
    CHECK(px.at(0, 0, 2) == 128);
    CHECK(px.at(1, 2, 1) == 255);
    CHECK(px.at(1, 2, 2) == 0);
    CHECK(px.at(1, 1, 0) == 0);
    CHECK(px.values[(1 * 3 + 2) * 3 + 1] == 255);  // row = keyframe, column = joint, channel = axis
    const auto n = to_network(px);
    CHECK(n.data[0] == -1.0f);                     // channel R plane first
    CHECK(n.data[2 * 6 + 0] == doctest::Approx(128 / 127.5 - 1));  // B plane, (0, 0)
    CHECK(n.data[1 * 6 + 0] == 1.0f);
    auto n2 = n;
    n2.data[0] = 3.0f;
    n2.data[1] = -7.0f;
    const auto px2 = from_network(n2);
    CHECK(px2.values[0] == 255);
    CHECK(px2.values[3] == 0);
    n2.data.pop_back();
    CHECK_THROWS_AS(from_network(n2), shape_error);
    CHECK(decode_angle(0, r) == -90);
    CHECK(decode_angle(255, r) == 90);
    // A range recorded for another shape is refused.
    CHECK_THROWS_AS(encode(k, angle_range{-90, 90, 9, 23}), shape_error);
    CHECK_THROWS_AS(encode(k, angle_range{5, 5, 0, 0}), value_error);
}

TEST_CASE("codec: range JSON save/load and its errors")
{
    namespace fs = std::filesystem;
    const fs::path dir = fs::temp_directory_path() / ("handemo_codec_test_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    const angle_range r{-97.25, 133.5, 9, 23};
    save_range(dir / "range.json", r);
    const angle_range l = load_range(dir / "range.json");
    CHECK(l.p_min == r.p_min);
    CHECK(l.p_max == r.p_max);
    CHECK(l.keyframes == 9);
    CHECK(l.joints == 23);
    auto expect_error = [&](const std::string& text, const std::string& needle) {
        const fs::path p = dir / "bad.json";
        write_file_atomic(p, text);
        try {
            (void)load_range(p);
            FAIL("no error for " << text);
        } catch (const format_error& e) {
            const std::string what = e.what();
            CHECK_MESSAGE(what.find("bad.json") != std::string::npos, what);
            CHECK_MESSAGE(what.find(needle) != std::string::npos, what);
        }
    };
    expect_error("{\"p_min\": 1, ", "malformed");
    expect_error("[1, 2]", "object");
    expect_error(R"({"format": "handemo-range/1", "p_max": 5, "keyframes": 9, "joints": 23})", "'p_min'");
    expect_error(R"({"format": "handemo-range/1", "p_min": 5, "p_max": 5, "keyframes": 9, "joints": 23})", "'p_max'");
    expect_error(R"({"format": "handemo-range/1", "p_min": 0, "p_max": "x", "keyframes": 9, "joints": 23})", "'p_max'");
    expect_error(R"({"format": "other", "p_min": 0, "p_max": 1, "keyframes": 9, "joints": 23})", "'format'");
    expect_error(R"({"format": "handemo-range/1", "p_min": 0, "p_max": 1, "keyframes": -9, "joints": 23})", "'keyframes'");
    expect_error(R"({"format": "handemo-range/1", "p_min": 0, "p_max": 1, "keyframes": 9})", "'joints'");
    // Numbers beyond double: nlohmann throws out_of_range while parsing; it must surface as a format_error.
    expect_error(R"({"format": "handemo-range/1", "p_min": 1e400, "p_max": 1, "keyframes": 9, "joints": 23})", "1e400");
    expect_error(R"({"format": "handemo-range/1", "p_min": 0, "p_max": -1e400, "keyframes": 9, "joints": 23})", "out of range");
    expect_error(R"({"format": "handemo-range/1", "p_min": 0, "p_max": 1, "keyframes": 1e400, "joints": 23})", "out of range");
    CHECK_THROWS_AS(load_range(dir / "missing.json"), io_error);
    CHECK_THROWS_AS(save_range(dir / "x.json", angle_range{1, 0, 9, 23}), value_error);
    fs::remove_all(dir);
}

TEST_CASE("codec: per-channel ranges (handemo-range/2) round trip within each channel's own bound")
{
    std::mt19937_64 g(5);
    const std::size_t J = 4, K = 9;
    std::vector<keyframes<9>> set;
    // channel widths differ by 100x; channel 5 winds (its values are one track shifted by whole turns)
    for (int s = 0; s < 20; ++s) {
        auto kf = keyframes<9>::make(J, K);
        for (std::size_t i = 0; i < K; ++i)
            for (std::size_t c = 0; c < J * 3; ++c) {
                const double u = static_cast<double>(g() >> 11) * 0x1.0p-53 - 0.5;
                double v = 10.0 * static_cast<double>(c) + u * (c == 0 ? 1.0 : 100.0);
                if (c == 5) v = 170.0 + 15.0 * u + 360.0 * (s % 5 - 2);  // wound by up to +-720
                kf.angles[i * J * 3 + c] = v;
            }
        set.push_back(kf);
    }
    const angle_range r = compute_channel_range(set);
    REQUIRE(r.per_channel());
    CHECK(r.lo.size() == J * 3);
    CHECK_NOTHROW(r.validate());
    // a narrow channel gets a fine resolution; the wound channel comes back next to its reference
    CHECK(r.hi[0] - r.lo[0] == doctest::Approx(20.0));  // min_span
    CHECK(r.hi[5] - r.lo[5] < 40.0);
    CHECK(std::abs(wrap_angle_deg(r.center[5] - 170.0)) < 3.0);
    for (std::size_t ch = 0; ch < J * 3; ++ch) {
        double worst = 0;
        for (const auto& kf : set) {
            const auto back = decode(encode(kf, r), r);
            for (std::size_t i = 0; i < K; ++i) {
                const double a = kf.angles[i * J * 3 + ch];
                if (!r.contains(a, ch)) continue;
                worst = std::max(worst, std::abs(wrap_angle_deg(back.angles[i * J * 3 + ch] - a)));
            }
        }
        CHECK(worst <= r.channel_roundtrip_error(ch) * (1 + 1e-12));
    }
    CHECK(r.channel_roundtrip_error(0) < 0.05);  // 20 deg / 510, against the global range's (p_max - p_min) / 510
    CHECK(compute_range(set).max_roundtrip_error() > 2.0);
}

TEST_CASE("codec: handemo-range/2 files save and load; handemo-range/1 files still load as one range")
{
    const auto dir = std::filesystem::temp_directory_path() / "handemo_range_v2";
    std::filesystem::create_directories(dir);
    std::mt19937_64 g(9);
    std::vector<keyframes<9>> set;
    for (int s = 0; s < 4; ++s) set.push_back(random_keyframes<9>(3, 9, g, -50, 60));
    const auto r = compute_channel_range(set);
    save_range(dir / "r2.json", r);
    const auto back = load_range(dir / "r2.json");
    CHECK(back.per_channel());
    CHECK(back.center == r.center);
    CHECK(back.lo == r.lo);
    CHECK(back.hi == r.hi);
    CHECK(encode(set[0], back).values == encode(set[0], r).values);
    const auto v1 = parse_range(R"({"format":"handemo-range/1","p_min":-10,"p_max":30,"keyframes":9,"joints":3})", "old.json");
    CHECK_FALSE(v1.per_channel());
    CHECK(v1.lo_of(4) == -10.0);
    CHECK(v1.half_span(4) == 20.0);
    CHECK(v1.to_frame(725.0, 2) == 725.0);  // a global range does not wrap
    // malformed per-channel fields are refused naming the field
    CHECK_THROWS_WITH_AS(parse_range(R"({"format":"handemo-range/2","p_min":-10,"p_max":30,"keyframes":9,"joints":1,"center":[0,0,0],"lo":[0,0],"hi":[1,1,1]})", "bad.json"),
                         doctest::Contains("field 'lo'"), format_error);
    CHECK_THROWS_WITH_AS(parse_range(R"({"format":"handemo-range/2","p_min":-10,"p_max":30,"keyframes":9,"joints":1,"center":[0,0,0],"lo":[0,5,0],"hi":[1,1,1]})", "bad.json"),
                         doctest::Contains("channel 1"), format_error);
    CHECK_THROWS_WITH_AS(parse_range(R"({"format":"handemo-range/3","p_min":-10,"p_max":30,"keyframes":9,"joints":1})", "bad.json"),
                         doctest::Contains("handemo-range/2"), format_error);
}
