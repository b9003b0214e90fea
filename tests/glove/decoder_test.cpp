// The profile parser and the report decoder on hand-made byte strings: values, endianness, fixed-point
// scale, clocks and counters with wrap-around, every kind of malformed report (refused whole, the
// decoder's state unchanged), and encode -> decode round trips.
#include "helpers.hpp"

#include <doctest/doctest.h>

#include <bit>
#include <cmath>
#include <limits>

using namespace handemo;
using namespace glove_test;

TEST_CASE("the shipped profiles parse")
{
    const auto imu = imu_profile();
    CHECK(imu.imus.size() == 7);
    CHECK(imu.flexes.empty());
    CHECK(imu.back_index() == 0);
    CHECK(imu.has_timestamp);
    CHECK(imu.has_sequence);
    CHECK(imu.reports.size() == 1);
    CHECK(imu.reports[0].size == 64);
    const auto flex = flex_profile();
    CHECK(flex.flexes.size() == 15);
    CHECK(flex.imus.empty());
    CHECK(!flex.has_timestamp);
    CHECK(flex.reports[0].size == 33);
    // copies keep their own sensor pointers
    const glove_profile copy = imu;
    CHECK(copy.imus[3] != imu.imus[3]);
    CHECK(copy.imus[3]->name == "middle");
}

TEST_CASE("decode a hand-made IMU report")
{
    const auto p = imu_profile();
    report_decoder d(p);
    auto q = identity7();
    q[2] = {0.5, 0.5, -0.5, 0.5};  // exact in Q14
    auto b = imu_report(7, 1234, q);
    glove_sample s;
    auto r = d.decode(b, 10.0, s);
    REQUIRE(r.fault == report_fault::none);
    CHECK(r.frame);
    CHECK(s.device_time == 0);  // the first timestamp is the origin
    CHECK(s.sequence == 0);
    CHECK(s.host_time == 10.0);
    CHECK(s.imu[2].w == doctest::Approx(0.5));
    CHECK(s.imu[2].y == doctest::Approx(-0.5));
    CHECK(s.imu[0].w == doctest::Approx(1));
    // the next report 10 ms later, two reports dropped in between
    b = imu_report(10, 1244, q);
    r = d.decode(b, 10.01, s);
    CHECK(r.fault == report_fault::none);
    CHECK(r.dropped == 2);
    CHECK(s.sequence == 3);
    CHECK(s.device_time == doctest::Approx(0.010));
}

TEST_CASE("counters and clocks wrap around")
{
    const auto p = imu_profile();
    report_decoder d(p);
    glove_sample s;
    CHECK(d.decode(imu_report(254, 0xfffffff0u, identity7()), 0, s).fault == report_fault::none);
    const auto r = d.decode(imu_report(1, 0x00000010u, identity7()), 0, s);  // 255, 0 missing; clock wrapped
    CHECK(r.fault == report_fault::none);
    CHECK(r.dropped == 2);
    CHECK(s.device_time == doctest::Approx(0.032));
}

TEST_CASE("malformed reports are refused whole with what was wrong")
{
    const auto p = imu_profile();
    report_decoder d(p);
    glove_sample s;
    auto q = identity7();
    REQUIRE(d.decode(imu_report(1, 100, q), 0, s).frame);

    auto short_b = imu_report(2, 110, q);
    short_b.resize(40);
    auto r = d.decode(short_b, 0, s);
    CHECK(r.fault == report_fault::short_report);
    CHECK(r.message.find("40 bytes, expected at least 64") != std::string::npos);

    auto wrong = imu_report(2, 110, q);
    wrong[0] = 9;
    r = d.decode(wrong, 0, s);
    CHECK(r.fault == report_fault::unknown_id);
    CHECK(r.message.find("report id 9") != std::string::npos);
    CHECK(d.decode(std::vector<std::uint8_t>{}, 0, s).fault == report_fault::unknown_id);

    auto zero = q;
    zero[4] = {0, 0, 0, 0};
    r = d.decode(imu_report(2, 110, zero), 0, s);
    CHECK(r.fault == report_fault::non_unit_quaternion);
    CHECK(r.message.find("sensor 'ring'") != std::string::npos);
    auto big = q;
    big[1] = {1.5, 0, 0, 0};
    CHECK(d.decode(imu_report(2, 110, big), 0, s).fault == report_fault::non_unit_quaternion);

    r = d.decode(imu_report(2, 90, q), 0, s);
    CHECK(r.fault == report_fault::clock_backwards);
    r = d.decode(imu_report(1, 120, q), 0, s);
    CHECK(r.fault == report_fault::out_of_range);  // the counter repeats

    // none of those changed the state: the next good report continues from counter 1 and 100 ms
    auto ok = q;
    ok[3] = {0, 1, 0, 0};
    r = d.decode(imu_report(2, 110, ok), 0, s);
    CHECK(r.fault == report_fault::none);
    CHECK(r.dropped == 0);
    CHECK(s.device_time == doctest::Approx(0.010));
    CHECK(s.imu[3].x == doctest::Approx(1));
    CHECK(s.imu[4].w == doctest::Approx(1));
}

TEST_CASE("float quaternions: NaN is refused; big-endian flex values and their range")
{
    const auto p = parse_glove_profile(R"({"format": "handemo-glove-profile/1", "name": "t", "back_sensor": "b",
        "reports": [{"id": 3, "fields": [
          {"name": "b", "kind": "quaternion", "bone": "palm", "offset": 1, "type": "f32", "order": "xyzw"},
          {"name": "f", "kind": "flex", "bone": "index_proximal", "offset": 17, "type": "u16", "endian": "big",
           "range": [0, 1000], "flat": 100, "fist": 900, "scale": 2}]}]})");
    report_decoder d(p);
    auto put = [](std::vector<std::uint8_t>& b, std::size_t at, float v) {
        const auto u = std::bit_cast<std::uint32_t>(v);
        for (int i = 0; i < 4; ++i) b[at + static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(u >> (8 * i));
    };
    std::vector<std::uint8_t> b(19, 0);
    b[0] = 3;
    put(b, 1, 0), put(b, 5, 0), put(b, 9, 0), put(b, 13, 1);  // x y z w
    b[17] = 0x01, b[18] = 0x2c;                                // 300 big-endian, / scale 2 = 150
    glove_sample s;
    auto r = d.decode(b, 0, s);
    REQUIRE(r.fault == report_fault::none);
    CHECK(s.imu[0].w == 1);
    CHECK(s.flex[0] == 150);
    put(b, 5, std::numeric_limits<float>::quiet_NaN());
    r = d.decode(b, 0, s);
    CHECK(r.fault == report_fault::not_finite);
    CHECK(r.message.find("NaN") != std::string::npos);
    put(b, 5, 0);
    b[17] = 0x0f, b[18] = 0xa0;  // 4000 / 2 = 2000 > 1000
    r = d.decode(b, 0, s);
    CHECK(r.fault == report_fault::out_of_range);
    CHECK(r.message.find("sensor 'f': value 2000") != std::string::npos);
}

TEST_CASE("profile errors name the field")
{
    auto bad = [](const std::string& fields, const std::string& extra = "") {
        return R"({"format": "handemo-glove-profile/1", "name": "t", "back_sensor": "b")" + extra + R"(, "reports": [{"id": 1, "fields": [)" + fields + "]}]}";
    };
    const std::string back = R"({"name": "b", "kind": "quaternion", "bone": "palm", "offset": 1})";
    CHECK_THROWS_WITH_AS(parse_glove_profile(bad(R"({"name": "b", "kind": "quaternion", "bone": "elbow", "offset": 1})"), "p.json"),
                         doctest::Contains("p.json: reports[0].fields[0]: bone 'elbow' is not a joint"), format_error);
    CHECK_THROWS_WITH_AS(parse_glove_profile(bad(back + R"(, {"kind": "flex", "bone": "index_proximal", "offset": 5})")),
                         doctest::Contains("fields[1]: bytes 5..6 overlap"), format_error);
    CHECK_THROWS_WITH_AS(parse_glove_profile(bad(back + R"(, {"kind": "gyro", "offset": 20})")),
                         doctest::Contains("kind 'gyro' is not"), format_error);
    CHECK_THROWS_WITH_AS(parse_glove_profile(bad(back + R"(, {"kind": "flex", "bone": "index_proximal", "offset": 9, "type": "u12"})")),
                         doctest::Contains("type 'u12'"), format_error);
    CHECK_THROWS_WITH_AS(parse_glove_profile(bad(R"({"name": "c", "kind": "quaternion", "bone": "index_distal", "offset": 1})")),
                         doctest::Contains("back_sensor 'b' is not a quaternion field"), format_error);
    CHECK_THROWS_WITH_AS(parse_glove_profile(R"({"format": "x"})"), doctest::Contains("expected 'handemo-glove-profile/1'"), format_error);
    CHECK_THROWS_WITH_AS(parse_glove_profile("{"), doctest::Contains("parse error"), format_error);
}

TEST_CASE("encode_reports is the decoder's inverse")
{
    for (const auto& p : {imu_profile(), flex_profile()}) {
        report_decoder d(p);
        glove_sample in;
        in.imu.resize(p.imus.size());
        for (std::size_t k = 0; k < in.imu.size(); ++k) in.imu[k] = normalized({1, 0.1 * double(k), -0.2, 0.05});
        for (std::size_t k = 0; k < p.flexes.size(); ++k) in.flex.push_back(600 + 100.0 * double(k));
        glove_sample out;
        for (int tick = 0; tick < 3; ++tick) {
            for (const auto& b : encode_reports(p, in, static_cast<std::uint64_t>(tick), 0.01 * tick)) {
                const auto r = d.decode(b, 0.5 * tick, out);
                REQUIRE(r.fault == report_fault::none);
                CHECK(r.dropped == 0);
            }
        }
        CHECK(out.sequence == 2);
        for (std::size_t k = 0; k < in.imu.size(); ++k) CHECK(angle_between_deg(in.imu[k], out.imu[k]) < 0.01);
        for (std::size_t k = 0; k < in.flex.size(); ++k) CHECK(out.flex[k] == in.flex[k]);
        if (p.has_timestamp) CHECK(out.device_time == doctest::Approx(0.02));
        else CHECK(std::isnan(out.device_time));
    }
}
