// The glove protocols and their transports without hardware: Senso JSON lines from a loopback TCP server
// (both hands, a disconnect and a reconnect, vibration sent back), an OpenGloves device on a pseudo-terminal
// (every field of the alpha encoding, partial lines, garbage, the cable pulled mid-line), 5DT Data Glove
// Ultra reports through the replay transport, and round trips pose -> simulated messages -> decoder -> pose
// within what each glove can sense.
#include "helpers.hpp"

#include <handemo/motion/synth.hpp>

#include <doctest/doctest.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <pty.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <random>
#include <string>
#include <thread>

using namespace handemo;
using namespace glove_test;

namespace {

namespace fs = std::filesystem;

decode_result decode_line(glove_decoder& d, std::string_view line, glove_sample& out)
{
    return d.decode(std::span(reinterpret_cast<const std::uint8_t*>(line.data()), line.size()), 0, out);
}

/// The largest difference of the sensed angles (those with a flex sensor, or every joint of `all`).
double worst_sensed(const glove_profile& p, const double* want, const double* got)
{
    const skeleton hand = hand_skeleton();
    double w = 0;
    for (const auto* f : p.flexes) {
        const std::size_t i = hand.index_of(f->bone) * 3 + static_cast<std::size_t>(f->rotation_axis);
        w = std::max(w, std::abs(want[i] - got[i]));
    }
    return w;
}

/// A pose within what a flex glove can represent: each sensed angle clamped between its flat and fist
/// readings' angles (and the hand model's limits).
std::vector<double> representable(const glove_profile& p, const double* a)
{
    const skeleton hand = hand_skeleton();
    std::vector<double> out(a, a + hand_joint_count * 3);
    for (const auto* f : p.flexes) {
        const std::size_t j = hand.index_of(f->bone), ax = static_cast<std::size_t>(f->rotation_axis);
        const double lo_v = (f->range_min - f->flat) / (f->fist - f->flat) * f->fist_angle, hi_v = (f->range_max - f->flat) / (f->fist - f->flat) * f->fist_angle;
        out[j * 3 + ax] = std::clamp(out[j * 3 + ax], std::max(std::min(lo_v, hi_v), hand.joints[j].lower_limit[ax]),
                                     std::min(std::max(lo_v, hi_v), hand.joints[j].upper_limit[ax]));
    }
    return out;
}

/// A loopback TCP server on an ephemeral port.
struct loopback_server {
    int fd = -1, port = 0;
    loopback_server()
    {
        fd = ::socket(AF_INET, SOCK_STREAM, 0);
        sockaddr_in a{};
        a.sin_family = AF_INET, a.sin_addr.s_addr = htonl(INADDR_LOOPBACK), a.sin_port = 0;
        REQUIRE(::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0);
        socklen_t len = sizeof a;
        ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len);
        port = ntohs(a.sin_port);
        REQUIRE(::listen(fd, 4) == 0);
    }
    ~loopback_server()
    {
        if (fd >= 0) ::close(fd);
    }
    std::string address() const { return "127.0.0.1:" + std::to_string(port); }
    int accept_one() const { return ::accept(fd, nullptr, nullptr); }
};

void send_all(int fd, const std::string& s)
{
    std::size_t done = 0;
    while (done < s.size()) {
        const auto n = ::send(fd, s.data() + done, s.size() - done, MSG_NOSIGNAL);
        if (n <= 0) return;
        done += static_cast<std::size_t>(n);
    }
}

/// Coupled poses for the IMU gloves (MCP = PIP, any DIP: the Senso bend sees it), thumb CMC = MCP.
std::vector<double> coupled_pose(std::mt19937& g)
{
    const skeleton hand = hand_skeleton();
    std::uniform_real_distribution<double> bend(0, 85), abd(-15, 15), dip(0, 80);
    std::vector<double> a(hand_joint_count * 3, 0.0);
    for (std::size_t f = 1; f < 5; ++f) {
        const double b = bend(g);
        a[hand_index::finger_joint(f, 1) * 3 + 0] = b, a[hand_index::finger_joint(f, 1) * 3 + 2] = abd(g);
        a[hand_index::finger_joint(f, 2) * 3 + 0] = b;
        a[hand_index::finger_joint(f, 3) * 3 + 0] = dip(g);
    }
    const double tb = std::uniform_real_distribution<double>(0, 40)(g);
    a[hand_index::finger_joint(0, 1) * 3 + 0] = tb, a[hand_index::finger_joint(0, 1) * 3 + 2] = std::uniform_real_distribution<double>(-30, 10)(g);
    a[hand_index::finger_joint(0, 2) * 3 + 0] = tb;
    a[hand_index::finger_joint(0, 3) * 3 + 0] = std::uniform_real_distribution<double>(0, 70)(g);
    for (std::size_t i = 0; i < a.size(); ++i) a[i] = std::clamp(a[i], hand.joints[i / 3].lower_limit[i % 3], hand.joints[i / 3].upper_limit[i % 3]);
    return a;
}

}  // namespace

TEST_CASE("senso: a hand-made position packet, both hands, and every fault refused with the state kept")
{
    senso_decoder right(hand_side::right), left(hand_side::left);
    const std::string good =
        R"({"src":"aa:bb","type":"position","data":{"type":"rh","palm":{"pos":[0.1,0.2,0.3],"quat":[1,0,0,0]},"wrist":{"quat":[1,0,0,0]},)"
        R"("fingers":[{"quat":[0.7071068,0.7071068,0,0],"quat2":[1,0,0,0],"ang":[0.1,0.2],"bend":0.0},{"quat":[0,1,0,0],"ang":[0,0],"bend":0.5},)"
        R"({"quat":[1,0,0,0],"bend":0.25},{"quat":[1,0,0,0],"bend":1.0},{"quat":[0.5,0.5,0.5,0.5],"bend":-0.25}]}})";
    glove_sample s;
    auto r = decode_line(right, good, s);
    REQUIRE(r.fault == report_fault::none);
    REQUIRE(r.frame);
    REQUIRE(s.imu.size() == 7);
    CHECK(s.imu[1].w == doctest::Approx(0.7071068));
    CHECK(s.imu[2].x == doctest::Approx(1));
    CHECK(s.imu[5].y == doctest::Approx(0.5));
    REQUIRE(s.flex.size() == 4);
    CHECK(s.flex[0] == 0.5);
    CHECK(s.flex[3] == -0.25);
    CHECK(right.last_packet().source == "aa:bb");
    CHECK(right.last_packet().palm_position[2] == doctest::Approx(0.3));
    CHECK(right.last_packet().angles[0][1] == doctest::Approx(0.2));
    // the same packet for the left decoder is the other hand: skipped and counted
    CHECK(!decode_line(left, good, s).frame);
    CHECK(left.other_hand() == 1);
    // a left-hand packet is mirrored onto the right-hand model: x kept, y and z negated
    std::string lh = good;
    lh.replace(lh.find("\"rh\""), 4, "\"lh\"");
    REQUIRE(decode_line(left, lh, s).frame);
    CHECK(s.imu[5].x == doctest::Approx(0.5));
    CHECK(s.imu[5].y == doctest::Approx(-0.5));
    CHECK(s.imu[5].z == doctest::Approx(-0.5));
    // other packet types are skipped
    CHECK(!decode_line(right, R"({"type":"battery","data":{"level":80}})", s).frame);
    CHECK(right.other_packets() == 1);

    auto bad = [&](std::string line, report_fault want, const char* says) {
        glove_sample o;
        const auto res = decode_line(right, line, o);
        CHECK_MESSAGE(res.fault == want, line);
        CHECK_MESSAGE(res.message.find(says) != std::string::npos, res.message);
        CHECK(!res.frame);
    };
    auto edit = [&](const std::string& from, const std::string& to) {
        std::string l = good;
        l.replace(l.find(from), from.size(), to);
        return l;
    };
    bad(good.substr(0, good.size() / 2), report_fault::syntax, "not a JSON object");  // a cut line
    bad("\x01\x02garbage", report_fault::syntax, "not a JSON object");
    bad("[1,2,3]", report_fault::syntax, "not a JSON object");
    bad(std::string(20000, '[') + std::string(20000, ']'), report_fault::syntax, "nested deeper than 8 levels");
    bad(R"({"data":{}})", report_fault::missing_field, "no \"type\"");
    bad(edit("\"rh\"", "\"xx\""), report_fault::missing_field, "\"rh\" or \"lh\"");
    bad(edit("\"quat2\":[1,0,0,0],", ""), report_fault::missing_field, "finger thumb: no \"quat2\"");
    bad(edit("[0,1,0,0]", "[0,2,0,0]"), report_fault::non_unit_quaternion, "finger index: quaternion norm 2");
    bad(edit("\"bend\":1.0", "\"bend\":7"), report_fault::out_of_range, "finger ring: bend 7");
    bad(edit("\"bend\":0.25", "\"bend\":\"x\""), report_fault::syntax, "finger middle: \"bend\" is not a number");
    bad(edit("[0.5,0.5,0.5,0.5]", "[0.5,0.5,0.5]"), report_fault::syntax, "finger pinky: \"quat\" is not [w, x, y, z]");
    bad(edit("\"pos\":[0.1,0.2,0.3]", "\"pos\":[0.1]"), report_fault::syntax, "palm: \"pos\"");
    // nothing refused changed the state: the last good packet is still the newest
    CHECK(right.last_packet().bend[4] == -0.25);

    // vibration out
    const auto v = senso_vibration("aa:bb", "index", 500, 7);
    CHECK(v == "{\"data\":{\"dur\":500,\"str\":7,\"type\":\"index\"},\"dst\":\"aa:bb\",\"type\":\"vibration\"}\n");
    CHECK_THROWS_AS(senso_vibration("aa:bb", "elbow", 500, 7), value_error);
    CHECK_THROWS_AS(senso_vibration("aa:bb", "index", 500, 11), value_error);
}

TEST_CASE("senso round trip: pose -> packets of either hand -> decoder -> pose, every joint within 0.01 degrees")
{
    const glove_profile p = senso_profile();
    const glove_simulator sim(p, 7, 20);
    std::vector<double> flat(hand_joint_count * 3, 0.0);
    for (hand_side h : {hand_side::right, hand_side::left}) {
        senso_decoder d(h);
        glove_sample s;
        REQUIRE(decode_line(d, senso_position_line(sim.sample(flat.data(), 0), h), s).frame);
        const hand_solver solver(p, calibrate_glove(p, std::vector<glove_sample>{s}));
        std::mt19937 g(3);
        double worst = 0;
        std::vector<double> out(hand_joint_count * 3);
        for (int it = 0; it < 200; ++it) {
            const auto a = coupled_pose(g);
            REQUIRE(decode_line(d, senso_position_line(sim.sample(a.data(), 0), h), s).frame);
            solver.solve(s, out.data());
            for (std::size_t i = 0; i < a.size(); ++i) worst = std::max(worst, std::abs(a[i] - out[i]));
        }
        MESSAGE("senso ", to_string(h), " hand: worst joint error ", worst, " deg on coupled poses (DIP free: the bend value)");
        CHECK(worst < 0.01);
    }
}

TEST_CASE("senso over loopback TCP: both hands, vibration sent, a disconnect and a reconnect through the reader thread")
{
    const auto dir = fs::temp_directory_path() / ("handemo_glove_senso_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    const glove_profile p = senso_profile();
    const glove_simulator sim(p, 2, 15);
    const clip c = synthesize(hand_motion::gripping, emotion::neutral, 0, 1, 100.0);
    std::vector<double> flat(hand_joint_count * 3, 0.0);
    // both hands' packets of frames [from, from + n), about a millisecond apart
    auto send_lines = [&](int fd, std::size_t from, std::size_t n) {
        for (std::size_t i = from; i < from + n; ++i) {
            const double* a = i < 60 ? flat.data() : c.frame_angles(i % c.frames);
            const glove_sample s = sim.sample(a, 0);
            send_all(fd, senso_position_line(s, hand_side::right) + "\n" + senso_position_line(s, hand_side::left) + "\n");
            std::this_thread::sleep_for(std::chrono::milliseconds(1));
        }
    };
    loopback_server server;
    std::string vibration;
    std::thread glove([&] {
        int fd = server.accept_one();
        send_lines(fd, 0, 100);
        // the vibration command the client sends after its first samples
        std::string got;
        char ch;
        while (got.find('\n') == std::string::npos && ::recv(fd, &ch, 1, 0) == 1) got += ch;
        vibration = got;
        send_all(fd, "{\"src\":\"aa\",\"type\":\"position\",\"data\":{\"type\":\"rh\",\"pal");  // closed mid-line
        ::close(fd);
        fd = server.accept_one();  // the client reconnects
        ::close(server.fd);        // and after this connection, nothing listens any more
        server.fd = -1;
        send_lines(fd, 100, 50);
        ::close(fd);
    });
    auto tcp = std::make_unique<tcp_transport>(server.address());
    CHECK(tcp->name() == "TCP " + server.address());
    glove_reader reader(std::move(tcp), {.capacity = 4096, .poll = std::chrono::milliseconds(10), .reconnect_window = 0.5, .reconnect_poll = 0.02});
    record_options o;
    o.raw = dir / "senso.raw";
    o.out = dir / "senso.bvh";
    o.reconnect_window = 0.5;
    o.reconnect_poll = 0.01;
    o.read_timeout = std::chrono::milliseconds(50);
    // the lines come in bursts (timed on arrival), so the calibration is given rather than taken from the first 0.5 s
    glove_sample flat_sample;
    senso_decoder cd;
    REQUIRE(decode_line(cd, senso_position_line(sim.sample(flat.data(), 0), hand_side::right), flat_sample).frame);
    glove_recorder rec(reader, std::make_unique<senso_decoder>(hand_side::right), calibrate_glove(p, std::vector<glove_sample>{flat_sample}), o);
    std::vector<std::string> warnings;
    rec.on_warning = [&](const std::string& w) { warnings.push_back(w); };
    bool sent = false;
    std::string error;
    try {
        while (rec.step())
            if (!sent && rec.stats().samples >= 10) reader.write_text(senso_vibration("aa", "index", 200, 5)), sent = true;
    } catch (const device_error& e) {
        error = e.what();
    }
    glove.join();
    const auto st = rec.stats();
    // the server that did not come back ended the recording, and the take written so far is a valid BVH
    const clip take = read_bvh(o.out);
    CHECK(take.frames == rec.take().frames);
    CHECK(take.frames > 5);  // 150 packets a millisecond or more apart
    CHECK(vibration == senso_vibration("aa", "index", 200, 5));
    CHECK(st.samples == 150);  // the right hand's packets; the left hand's are skipped
    CHECK(st.reconnects == 1);
    CHECK(st.malformed == 0);  // the cut line never became a report
    CHECK(error.find("TCP " + server.address() + " disconnected (the server closed the connection); no reconnect within") != std::string::npos);
    REQUIRE(warnings.size() >= 2);
    CHECK(warnings[0].find("disconnected (the server closed the connection); a partial line of 54 bytes was dropped") != std::string::npos);
    CHECK(warnings[1].find("reconnected to TCP 127.0.0.1:") != std::string::npos);
    // the raw copy of the lines holds both hands: the left hand's decoder records the left glove from it
    replay_transport rp(o.raw);
    record_options o2;
    o2.reconnect_window = 1;
    glove_recorder left(rp, std::make_unique<senso_decoder>(hand_side::left), std::nullopt, o2);
    left.run();
    CHECK(left.stats().samples == 150);
    CHECK(left.stats().reconnects == 1);
    CHECK(dynamic_cast<const senso_decoder&>(left.decoder()).other_hand() == 150);
    fs::remove_all(dir);
}

TEST_CASE("tcp transport: a refused connection and a bad address name what was tried")
{
    loopback_server s;  // bound and listening, then closed: the port refuses
    const std::string addr = s.address();
    ::close(s.fd);
    s.fd = ::socket(AF_INET, SOCK_STREAM, 0);
    const std::string want = "cannot connect to TCP " + addr;
    CHECK_THROWS_WITH_AS(tcp_transport{addr}, doctest::Contains(want.c_str()), device_error);
    CHECK_THROWS_WITH_AS(tcp_transport{"localhost"}, doctest::Contains("'localhost' is not HOST:PORT"), value_error);
}

TEST_CASE("opengloves: every field of the alpha encoding, and what is refused")
{
    opengloves_decoder d(1023);
    glove_sample s;
    auto r = decode_line(d, "A0B1023C512D100E900(AB)512(BB)0(CB)1023(DB)600(EB)400(BAA)200(BAB)300(BAC)400(BAD)500F700G300P800HIJKLMNO(ZV)5(ZG)0(ZH)1", s);
    REQUIRE(r.fault == report_fault::none);
    REQUIRE(r.frame);
    CHECK(r.warning == report_fault::none);
    const auto& st = d.state();
    CHECK(st.curl[1] == doctest::Approx(1.0));
    CHECK(st.curl[2] == doctest::Approx(512.0 / 1023));
    CHECK(st.splay[2] == doctest::Approx(1.0));
    CHECK(st.joint[1][3] == doctest::Approx(500.0 / 1023));
    CHECK(std::isnan(st.joint[2][0]));
    CHECK(st.joy_x == doctest::Approx(700.0 / 1023));
    CHECK(st.joy_y == doctest::Approx(300.0 / 1023));
    CHECK(st.trigger == doctest::Approx(800.0 / 1023));
    CHECK((st.joy_click && st.trigger_button && st.a && st.b && st.grab && st.pinch && st.menu && st.calibrate));
    CHECK(st.firmware_version == "5");
    CHECK(st.device_type == "0");
    CHECK(st.hand == "1");
    REQUIRE(s.flex.size() == 20);
    // index: its own joint values; middle: its curl for every joint; splay as sent
    CHECK(s.flex[3] == doctest::Approx(200.0 / 1023));
    CHECK(s.flex[4] == doctest::Approx(300.0 / 1023));
    CHECK(s.flex[5] == doctest::Approx(400.0 / 1023));
    CHECK(s.flex[6] == doctest::Approx(512.0 / 1023));
    CHECK(s.flex[8] == doctest::Approx(512.0 / 1023));
    CHECK(s.flex[17] == doctest::Approx(1.0));
    // buttons hold only while sent; a line of buttons alone is no frame
    r = decode_line(d, "J", s);
    CHECK(!r.frame);
    CHECK(d.state().a);
    CHECK(!d.state().b);
    // an unknown key is a warning, the rest of the line is used
    r = decode_line(d, "A10(QQ)5B20", s);
    CHECK(r.frame);
    CHECK(r.warning == report_fault::unknown_key);
    CHECK(r.warning_message == "unknown key (QQ) ignored");
    CHECK(d.state().curl[1] == doctest::Approx(20.0 / 1023));

    auto bad = [&](std::string_view line, report_fault want, const char* says) {
        const auto before = d.state().curl;
        glove_sample o;
        const auto res = decode_line(d, line, o);
        CHECK_MESSAGE(res.fault == want, line);
        CHECK_MESSAGE(res.message.find(says) != std::string::npos, res.message);
        CHECK(d.state().curl == before);  // refused whole: nothing changed
    };
    bad("A1024B0", report_fault::out_of_range, "A 1024 is above 1023");
    bad("A5B", report_fault::syntax, "key B has no value");
    bad("A5 x9", report_fault::syntax, "unexpected character 'x' at column 4");
    bad("A5\x07", report_fault::syntax, "unexpected character 0x07");
    bad("(AB5", report_fault::syntax, "unclosed or empty key at column 1");
    bad("A12345678901", report_fault::out_of_range, "too many digits");
    bad("(ZV)", report_fault::syntax, "info key (ZV) has no value");

    // commands out
    CHECK(opengloves_force_feedback({0, 0.25, 0.5, 1, 0.001}) == "A0B250C500D1000E1\n");
    CHECK_THROWS_AS(opengloves_force_feedback({0, 0, 2, 0, 0}), value_error);
    CHECK(opengloves_haptics(180, 0.5, 0.75) == "F180.00G0.50H0.75\n");
    CHECK_THROWS_AS(opengloves_haptics(180, 0.5, 1.5), value_error);
    CHECK_THROWS_AS(opengloves_decoder(0), value_error);
}

TEST_CASE("opengloves round trip on the synthetic data set: sensed joints within half a reading step")
{
    const glove_profile p = opengloves_profile();
    const glove_simulator sim(p);
    const hand_solver solver(p, default_calibration(p));
    for (int max : {1023, 4095}) {
        opengloves_decoder d(max);
        double worst = 0;
        std::vector<double> out(hand_joint_count * 3);
        glove_sample s;
        for (hand_motion m : all_hand_motions) {
            const clip c = synthesize(m, emotion::angry, 0, 3, 30.0);
            for (std::size_t f = 0; f < c.frames; ++f) {
                const auto a = representable(p, c.frame_angles(f));
                REQUIRE(decode_line(d, opengloves_line(sim.sample(a.data(), 0), max), s).frame);
                solver.solve(s, out.data());
                worst = std::max(worst, worst_sensed(p, a.data(), out.data()));
            }
        }
        const double step = 110.0 / max;  // the widest joint range over the analog steps
        MESSAGE("opengloves ", max, ": worst sensed joint error ", worst, " deg (half a step: ", step / 2, ")");
        CHECK(worst <= step / 2 + 1e-9);
    }
    // curls only: every joint of a finger at the same fraction of its fist angle
    opengloves_decoder d(4095);
    glove_sample s;
    REQUIRE(decode_line(d, "A0B2048C4095D0E0", s).frame);
    std::vector<double> out(hand_joint_count * 3);
    solver.solve(s, out.data());
    CHECK(out[hand_index::finger_joint(1, 1) * 3] == doctest::Approx(90 * 2048.0 / 4095));
    CHECK(out[hand_index::finger_joint(1, 3) * 3] == doctest::Approx(80 * 2048.0 / 4095));
    CHECK(out[hand_index::finger_joint(2, 2) * 3] == doctest::Approx(110));
}

TEST_CASE("opengloves on a pseudo-terminal: partial lines, garbage, every field, commands back, the cable pulled mid-line")
{
    int master = -1, slave = -1;
    char path[256];
    REQUIRE(::openpty(&master, &slave, path, nullptr, nullptr) == 0);
    auto serial = std::make_unique<serial_transport>(path, 115200);
    auto* port = serial.get();
    ::close(slave);  // the transport opened its own descriptor
    CHECK(port->name() == std::string("serial port ") + path);
    glove_reader reader(std::move(serial), {.capacity = 1024, .poll = std::chrono::milliseconds(10)});
    std::thread device([&] {
        auto w = [&](const std::string& s) { CHECK(::write(master, s.data(), s.size()) == static_cast<ssize_t>(s.size())); };
        for (int i = 0; i < 30; ++i) w("A" + std::to_string(i * 100) + "B2000C3000D100E4000(AB)2048(BB)2048(CB)2048(DB)2048(EB)2048\r\n");
        w("A1000B20");  // a line split over two writes
        std::this_thread::sleep_for(std::chrono::milliseconds(30));
        w("00C0D0E0\n");
        w("\x13\x88\xff garbage\n");                                   // noise
        w("A9999B0C0D0E0\n");                                           // above 4095
        w("A1B1C1D1E1(XY)3\n");                                         // an unknown key
        w(std::string(5000, 'A') + "\n");                               // an endless line, cut at 4096
        w("A0B0C0D0E0F2048G2048P100HIJKLMNO(ZV)7(ZG)1(ZH)0\n");         // every other field
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
        char buf[64] = {};
        pollfd pf{master, POLLIN, 0};
        const auto n = ::poll(&pf, 1, 2000) == 1 ? ::read(master, buf, sizeof buf - 1) : 0;  // the force feedback the host sent
        CHECK(std::string(buf, static_cast<std::size_t>(std::max<ssize_t>(n, 0))) == "A0B500C1000D0E0\n");
        w("A12B");  // the cable is pulled mid-line, after the host has read the start of the line
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
        ::close(master);
    });
    record_options o;
    o.read_timeout = std::chrono::milliseconds(50);
    glove_recorder rec(reader, std::make_unique<opengloves_decoder>(4095), std::nullopt, o);
    std::vector<std::string> warnings;
    rec.on_warning = [&](const std::string& w) { warnings.push_back(w); };
    bool sent = false;
    std::string error;
    try {
        while (rec.step())
            if (!sent && rec.stats().reports >= 36) reader.write_text("A0B500C1000D0E0\n"), sent = true;
    } catch (const device_error& e) {
        error = e.what();
    }
    device.join();
    reader.stop();
    const auto st = rec.stats();
    CHECK(st.reports == 36);
    CHECK(st.samples == 33);  // 30 + the split line + the unknown key's line + the last one
    CHECK(st.malformed == 3);
    CHECK(st.faults[static_cast<std::size_t>(report_fault::syntax)] == 2);  // the noise and the cut endless line
    CHECK(st.faults[static_cast<std::size_t>(report_fault::out_of_range)] == 1);
    CHECK(st.warnings == 1);
    CHECK(st.faults[static_cast<std::size_t>(report_fault::unknown_key)] == 1);
    CHECK(port->overlong_lines() == 1);
    CHECK(port->partial_lines() == 1);
    CHECK(error.find(std::string("serial port ") + path + " disconnected (the cable was pulled or the device reset); a partial line of 4 bytes was dropped") !=
          std::string::npos);
    const auto& state = dynamic_cast<const opengloves_decoder&>(rec.decoder()).state();
    CHECK(state.firmware_version == "7");
    CHECK(state.hand == "0");
    CHECK(state.trigger == doctest::Approx(100.0 / 4095));
    CHECK(state.menu);
    CHECK(std::any_of(warnings.begin(), warnings.end(), [](const std::string& w) { return w.find("unknown key (XY) ignored") != std::string::npos; }));
    CHECK_THROWS_WITH_AS(serial_transport{"/dev/handemo-no-such-port"}, doctest::Contains("cannot open serial port /dev/handemo-no-such-port"), device_error);
    CHECK_THROWS_AS((serial_transport{path, 1234}), value_error);
}

TEST_CASE("5dt: product ids, and reports through the replay transport round trip within half a reading step")
{
    CHECK(fivedt_product_id(14, hand_side::right) == 0x0000);
    CHECK(fivedt_product_id(14, hand_side::left) == 0x0001);
    CHECK(fivedt_product_id(5, hand_side::right) == 0x0010);
    CHECK(fivedt_product_id(5, hand_side::left) == 0x0011);
    CHECK_THROWS_AS(fivedt_profile(7), value_error);
    const auto p14 = fivedt_profile(14, hand_side::left);
    CHECK(*p14.vendor_id == 0x5d70);
    CHECK(p14.flexes.size() == 14);
    CHECK(p14.reports[0].size == 64);
    CHECK(p14.reports[0].id == -1);

    // a hand-made report: big-endian values, the abduction sensor 5 (index-middle)
    std::vector<std::uint8_t> b(64, 0);
    b[3 * 2] = 0x0b, b[3 * 2 + 1] = 0xb8;  // index near: 3000 = the fist
    b[5 * 2] = 0x07, b[5 * 2 + 1] = 0xd0;  // index-middle abduction: 2000, halfway
    report_decoder d(p14);
    glove_sample s;
    REQUIRE(d.decode(b, 0, s).frame);
    CHECK(s.flex[3] == 3000);
    std::vector<double> out(hand_joint_count * 3);
    hand_solver(p14, default_calibration(p14)).solve(s, out.data());
    CHECK(out[hand_index::finger_joint(1, 1) * 3] == doctest::Approx(90));
    CHECK(out[hand_index::finger_joint(1, 1) * 3 + 2] == doctest::Approx(-10));
    b.resize(63);
    CHECK(d.decode(b, 0, s).fault == report_fault::short_report);

    const auto dir = fs::temp_directory_path() / ("handemo_glove_5dt_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    for (int sensors : {14, 5}) {
        const auto p = fivedt_profile(sensors);
        const glove_simulator sim(p);
        const hand_solver solver(p, default_calibration(p));
        std::vector<std::vector<double>> poses;
        {
            raw_writer w(dir / "5dt.raw");
            std::size_t tick = 0;
            for (hand_motion m : {hand_motion::gripping, hand_motion::pointing, hand_motion::crawling}) {
                const clip c = synthesize(m, emotion::sad, 0, 4, 30.0);
                for (std::size_t f = 0; f < c.frames; ++f, ++tick) {
                    auto a = representable(p, c.frame_angles(f));
                    if (sensors == 5)  // one sensor per finger: the finger bends as a whole
                        for (std::size_t k = 0; k < 5; ++k) {
                            const auto* near = p.flexes[2 * k];
                            const auto* far = p.flexes[2 * k + 1];
                            const double frac = a[hand_skeleton().index_of(far->bone) * 3] / far->fist_angle;
                            a[hand_skeleton().index_of(near->bone) * 3] = frac * near->fist_angle;
                        }
                    poses.push_back(a);
                    for (auto& r : encode_reports(p, sim.sample(a.data(), 0), tick, 0)) w.write({std::move(r), tick / 75.0, 0});
                }
            }
        }
        replay_transport rp(dir / "5dt.raw");
        report_decoder dec(p);
        double worst = 0;
        std::size_t i = 0;
        while (auto r = rp.read(std::chrono::milliseconds(0))) {
            REQUIRE(dec.decode(r->bytes, r->host_time, s).frame);
            solver.solve(s, out.data());
            worst = std::max(worst, worst_sensed(p, poses[i++].data(), out.data()));
        }
        CHECK(i == poses.size());
        const double step = 110.0 / 2000;  // the widest angle per count
        MESSAGE("5dt ", sensors, " sensors: worst sensed joint error ", worst, " deg (half a count: ", step / 2, ")");
        CHECK(worst <= step / 2 + 1e-9);
    }
    fs::remove_all(dir);
}

TEST_CASE("choose_glove resolves --glove and its decoders")
{
    CHECK(choose_glove("senso").link == glove_link::tcp);
    CHECK(choose_glove("senso").default_device == "127.0.0.1:53450");
    CHECK(choose_glove("opengloves", hand_side::right, 14, 1023).link == glove_link::serial);
    CHECK_THROWS_AS(choose_glove("opengloves", hand_side::right, 14, 2000), value_error);
    CHECK(choose_glove("5dt", hand_side::left, 5).profile.name == "5dt-ultra-5-left");
    CHECK(choose_glove(std::string(HANDEMO_SOURCE_DIR) + "/examples/glove/imu7_example.json").kind == "profile");
    CHECK(dynamic_cast<senso_decoder*>(make_decoder(choose_glove("senso", hand_side::left)).get())->hand() == hand_side::left);
    CHECK(dynamic_cast<opengloves_decoder*>(make_decoder(choose_glove("opengloves", hand_side::right, 14, 1023)).get())->analog_max() == 1023);
    CHECK_THROWS_AS(choose_glove("/no/such/profile.json"), io_error);
}

TEST_CASE("the text decoders take any bytes: random lines and mutated good lines are decoded or refused, never more")
{
    const glove_profile sp = senso_profile();
    const glove_simulator sim(sp, 5);
    std::vector<double> pose(hand_joint_count * 3, 0.0);
    const std::string senso = senso_position_line(sim.sample(pose.data(), 0), hand_side::right);
    const std::string og = "A100B200C300D400E500(AB)10(BAA)20F30G40P50HIJ(ZV)1";
    std::mt19937 g(17);
    std::uniform_int_distribution<int> byte(0, 255);
    senso_decoder sd;
    opengloves_decoder od(1023);
    glove_sample s;
    std::size_t refused = 0, frames = 0;
    for (int it = 0; it < 3000; ++it) {
        std::string line = it % 3 == 0 ? std::string() : (it % 3 == 1 ? senso : og);
        const int edits = 1 + it % 4;
        for (int e = 0; e < edits; ++e) {
            const auto at = line.empty() ? 0 : static_cast<std::size_t>(byte(g)) % line.size();
            if (line.empty() || e % 2 == 0) line.insert(line.begin() + static_cast<std::ptrdiff_t>(at), static_cast<char>(byte(g)));
            else line[at] = static_cast<char>(byte(g));
        }
        for (glove_decoder* d : {static_cast<glove_decoder*>(&sd), static_cast<glove_decoder*>(&od)}) {
            const auto r = decode_line(*d, line, s);
            if (r.fault != report_fault::none) {
                ++refused;
                CHECK(!r.frame);
                CHECK(!r.message.empty());
            } else if (r.frame) {
                ++frames;
                for (const auto& q : s.imu) CHECK(std::abs(norm(q) - 1) < 1e-9);
                for (double v : s.flex) CHECK(std::isfinite(v));
            }
        }
    }
    CHECK(refused > 1000);
    CHECK(frames > 10);
}
