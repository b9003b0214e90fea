// hidapi end to end with a virtual HID device (Linux uhid): creates a device with the report layout of the
// 7-IMU example profile, finds it with enumerate_hid, opens it with hid_transport, sends input reports
// through the kernel and decodes what hidapi reads; checks a timeout, then destroys the device and expects
// a device_error naming it. Exits 77 (CTest: skipped, not passed) where /dev/uhid is missing or not
// writable, or the created hidraw node cannot be opened (permissions).
#include <handemo/glove.hpp>
#include <handemo/glove/hid.hpp>

#include <linux/uhid.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fcntl.h>
#include <thread>
#include <unistd.h>

using namespace handemo;

namespace {

constexpr int skipped = 77;
constexpr std::uint16_t vid = 0x1209, pid = 0x6a6e;

int failures = 0;
#define EXPECT(cond)                                                                      \
    do {                                                                                  \
        if (!(cond)) std::fprintf(stderr, "%s:%d: FAILED: %s\n", __FILE__, __LINE__, #cond), ++failures; \
    } while (0)

bool write_event(int fd, const uhid_event& ev)
{
    return ::write(fd, &ev, sizeof ev) == static_cast<ssize_t>(sizeof ev);
}

bool send_input(int fd, const std::vector<std::uint8_t>& report)
{
    uhid_event ev{};
    ev.type = UHID_INPUT2;
    ev.u.input2.size = static_cast<std::uint16_t>(report.size());
    std::memcpy(ev.u.input2.data, report.data(), report.size());
    return write_event(fd, ev);
}

}  // namespace

int main()
{
    const int fd = ::open("/dev/uhid", O_RDWR | O_CLOEXEC);
    if (fd < 0) {
        std::printf("skipped: cannot open /dev/uhid (%s): no virtual HID devices on this machine\n", std::strerror(errno));
        return skipped;
    }
    // Vendor page, report id 1, 63 bytes of input: the 64-byte report of imu7_example.json.
    const std::uint8_t rd[] = {0x06, 0x00, 0xff, 0x09, 0x01, 0xa1, 0x01, 0x85, 0x01, 0x15, 0x00, 0x26, 0xff, 0x00,
                               0x75, 0x08, 0x95, 0x3f, 0x09, 0x01, 0x81, 0x02, 0xc0};
    uhid_event ev{};
    ev.type = UHID_CREATE2;
    std::snprintf(reinterpret_cast<char*>(ev.u.create2.name), sizeof ev.u.create2.name, "handemo test glove");
    ev.u.create2.rd_size = sizeof rd;
    ev.u.create2.bus = 0x03;  // BUS_USB
    ev.u.create2.vendor = vid;
    ev.u.create2.product = pid;
    std::memcpy(ev.u.create2.rd_data, rd, sizeof rd);
    if (!write_event(fd, ev)) {
        std::printf("skipped: UHID_CREATE2 failed (%s)\n", std::strerror(errno));
        ::close(fd);
        return skipped;
    }
    std::vector<hid_device_entry> found;
    for (int i = 0; i < 50 && found.empty(); ++i) {
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
        found = enumerate_hid(vid, pid);
    }
    EXPECT(!found.empty());
    if (found.empty()) return 1;
    EXPECT(found.front().usage_page == 0xff00);
    std::unique_ptr<hid_transport> t;
    try {
        t = std::make_unique<hid_transport>("1209:6a6e", std::vector<std::vector<std::uint8_t>>{}, 65);
    } catch (const device_error& e) {
        std::printf("skipped: the virtual device exists but cannot be opened: %s\n", e.what());
        ::close(fd);
        return skipped;
    }
    const auto p = read_glove_profile(std::string(HANDEMO_SOURCE_DIR) + "/examples/glove/imu7_example.json");
    const glove_simulator sim(p, 2);
    std::vector<double> pose(hand_joint_count * 3, 0.0);
    pose[hand_index::finger_joint(1, 2) * 3] = 40;
    report_decoder d(p);
    glove_sample s;
    std::size_t frames = 0;
    for (std::uint64_t tick = 0; tick < 20; ++tick) {
        const auto reports = encode_reports(p, sim.sample(pose.data(), 0.01 * double(tick)), tick, 0.01 * double(tick));
        EXPECT(send_input(fd, reports.front()));
        const auto r = t->read(std::chrono::milliseconds(1000));
        EXPECT(r.has_value());
        if (!r) continue;
        EXPECT(r->bytes.size() == 64);
        const auto res = d.decode(r->bytes, r->host_time, s);
        EXPECT(res.fault == report_fault::none);
        EXPECT(res.dropped == 0);
        frames += res.frame;
    }
    EXPECT(frames == 20);
    EXPECT(std::abs(s.device_time - 0.19) < 1e-9);
    EXPECT(!t->read(std::chrono::milliseconds(50)).has_value());  // a timeout is not an error
    uhid_event destroy{};
    destroy.type = UHID_DESTROY;
    EXPECT(write_event(fd, destroy));
    bool threw = false;
    try {
        for (int i = 0; i < 20; ++i) (void)t->read(std::chrono::milliseconds(100));
    } catch (const device_error& e) {
        threw = std::string(e.what()).find("1209:6a6e") != std::string::npos;
    }
    EXPECT(threw);
    ::close(fd);
    std::printf("%s: 20 reports through /dev/uhid and hidapi, timeout, disconnect\n", failures ? "FAILED" : "passed");
    return failures ? 1 : 0;
}
