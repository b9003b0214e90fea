// Where glove reports come from, behind one small interface: a HID device (hid.hpp, hidapi), a serial
// line (serial.hpp, termios), a TCP line stream (tcp.hpp), a replay of a recorded report stream (the
// `--raw` file of `handemo glove record`), and an in-memory fake for tests that scripts reports, timeouts,
// disconnects and reconnects. A report is one HID input report or one text line (without its line end).
// A read that times out returns an empty std::optional (no data yet is not an error); a disconnect throws
// device_error naming the device. The reader thread (reader.hpp) wraps any of them.
//
// Raw stream file (`handemo-glove-raw/1`): the 8 bytes "HGLVRAW1", then one record per report:
// host time in seconds (float64, little-endian), length (uint16, little-endian), the report bytes. It is
// only ever appended to, so a crash loses at most the last record; a truncated last record is ignored
// by the replay and reported by truncated(). A record of length 0 marks a reconnect: the replay reads it
// as a disconnect (device_error) that reconnect() ends, so a recording replays as it was made.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/core/io.hpp>

#include <bit>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

namespace handemo {

/// @brief One report as received: its bytes (report id first for numbered reports) and host time.
struct hid_report {
    std::vector<std::uint8_t> bytes;
    double host_time = 0;  ///< seconds on the host's steady clock (or the recorded one, on replay)
    double arrival = 0;    ///< host seconds when the reader thread received it (0: read without one)
};

/// Seconds on the host's steady clock.
inline double host_seconds() noexcept
{
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

/// @brief A source of glove reports.
class glove_transport {
public:
    virtual ~glove_transport() = default;
    /// Human-readable device name for messages (path, VID:PID, replay file).
    virtual std::string name() const = 0;
    /// @brief Waits up to `timeout` for the next report.
    /// @return the report, or empty on timeout (and at the end of a replay, see finished()).
    /// @throws device_error naming the device when it is disconnected or fails.
    virtual std::optional<hid_report> read(std::chrono::milliseconds timeout) = 0;
    /// @brief Tries once to reopen the device after a disconnect. @return true when reading can go on.
    virtual bool reconnect() { return false; }
    /// True when no report will ever come again (the end of a replay).
    virtual bool finished() const { return false; }
    /// @brief Sends bytes to the glove (a command line of a text protocol: vibration, force feedback).
    /// @throws device_error naming the device.
    virtual void write(std::span<const std::uint8_t>) { throw device_error(name() + ": sending to the glove is not supported"); }
    /// Sends text (a command line with its line end).
    void write_text(std::string_view text) { write(std::span(reinterpret_cast<const std::uint8_t*>(text.data()), text.size())); }
    /// Reports lost because a queue between the device and its reader was full (reader.hpp).
    virtual std::size_t overruns() const { return 0; }
    /// @brief Sends a feature report (first byte: report id). @throws device_error.
    virtual void send_feature(std::span<const std::uint8_t>) { throw device_error(name() + ": feature reports are not supported"); }
    /// @brief Reads feature report `id` (up to `size` bytes, id included). @throws device_error.
    virtual std::vector<std::uint8_t> get_feature(std::uint8_t, std::size_t)
    {
        throw device_error(name() + ": feature reports are not supported");
    }
};

/// @brief Appends reports to a raw stream file (see the file comment), flushing every `flush_every`.
class raw_writer {
public:
    explicit raw_writer(const std::filesystem::path& path, std::size_t flush_every = 64) : path_(path), flush_every_(flush_every)
    {
        f_ = std::fopen(path.string().c_str(), "wb");
        if (!f_) throw io_error("raw_writer: cannot create " + path.string());
        if (std::fwrite("HGLVRAW1", 1, 8, f_) != 8) throw io_error("raw_writer: write failed for " + path.string());
    }
    raw_writer(const raw_writer&) = delete;
    raw_writer& operator=(const raw_writer&) = delete;
    ~raw_writer()
    {
        if (f_) std::fclose(f_);
    }
    void write(const hid_report& r)
    {
        std::uint8_t head[10];
        const auto t = std::bit_cast<std::uint64_t>(r.host_time);
        for (int i = 0; i < 8; ++i) head[i] = static_cast<std::uint8_t>(t >> (8 * i));
        const auto n = static_cast<std::uint16_t>(std::min<std::size_t>(r.bytes.size(), 65535));
        head[8] = static_cast<std::uint8_t>(n), head[9] = static_cast<std::uint8_t>(n >> 8);
        if (std::fwrite(head, 1, 10, f_) != 10 || std::fwrite(r.bytes.data(), 1, n, f_) != n)
            throw io_error("raw_writer: write failed for " + path_.string());
        if (++count_ % flush_every_ == 0) std::fflush(f_);
    }
    void flush() { std::fflush(f_); }

private:
    std::filesystem::path path_;
    std::size_t flush_every_, count_ = 0;
    std::FILE* f_ = nullptr;
};

/// @brief Parses a raw stream. @throws format_error when the magic is wrong.
/// @param truncated set to the byte offset of a truncated last record, or -1.
inline std::vector<hid_report> parse_raw_stream(std::string_view data, const std::string& source, long& truncated)
{
    if (data.size() < 8 || data.substr(0, 8) != "HGLVRAW1")
        throw format_error("glove replay: " + source + ": not a raw glove stream (expected the magic 'HGLVRAW1')");
    std::vector<hid_report> out;
    truncated = -1;
    std::size_t p = 8;
    while (p < data.size()) {
        if (data.size() - p < 10) {
            truncated = static_cast<long>(p);
            break;
        }
        std::uint64_t t = 0;
        for (int i = 0; i < 8; ++i) t |= static_cast<std::uint64_t>(static_cast<std::uint8_t>(data[p + static_cast<std::size_t>(i)])) << (8 * i);
        const std::size_t n = static_cast<std::uint8_t>(data[p + 8]) | (static_cast<std::size_t>(static_cast<std::uint8_t>(data[p + 9])) << 8);
        if (data.size() - p - 10 < n) {
            truncated = static_cast<long>(p);
            break;
        }
        hid_report r;
        r.host_time = std::bit_cast<double>(t);
        r.bytes.assign(reinterpret_cast<const std::uint8_t*>(data.data()) + p + 10, reinterpret_cast<const std::uint8_t*>(data.data()) + p + 10 + n);
        out.push_back(std::move(r));
        p += 10 + n;
    }
    return out;
}

/// @brief Replays a raw stream file: as fast as it is read, or in real time (sleeping to the recorded
/// gaps between reports, capped by the read timeout).
class replay_transport : public glove_transport {
public:
    explicit replay_transport(const std::filesystem::path& path, bool realtime = false) : path_(path), realtime_(realtime)
    {
        reports_ = parse_raw_stream(read_file(path), path.string(), truncated_);
    }
    std::string name() const override { return "replay " + path_.string(); }
    std::optional<hid_report> read(std::chrono::milliseconds timeout) override
    {
        if (next_ >= reports_.size()) return std::nullopt;
        if (reports_[next_].bytes.empty()) {
            ++next_;
            throw device_error("glove: " + name() + ": the device disconnected here during the recording");
        }
        if (realtime_) {
            const double now = host_seconds();
            if (next_ == 0) start_host_ = now, start_rec_ = reports_[0].host_time;
            const double due = start_host_ + (reports_[next_].host_time - start_rec_);
            if (due > now) {
                const double wait = std::min(due - now, std::chrono::duration<double>(timeout).count());
                std::this_thread::sleep_for(std::chrono::duration<double>(wait));
                if (host_seconds() < due) return std::nullopt;
            }
        }
        return reports_[next_++];
    }
    bool finished() const override { return next_ >= reports_.size(); }
    bool reconnect() override { return true; }
    /// Byte offset of a truncated last record that was ignored, or -1.
    long truncated() const noexcept { return truncated_; }
    std::size_t size() const noexcept { return reports_.size(); }

private:
    std::filesystem::path path_;
    bool realtime_;
    std::vector<hid_report> reports_;
    std::size_t next_ = 0;
    long truncated_ = -1;
    double start_host_ = 0, start_rec_ = 0;
};

/// @brief A scripted transport for tests: a queue of reports, timeouts, disconnects and the outcome of
/// reconnect attempts. An empty queue reads as a timeout (or finished(), once `close()` was called).
class fake_transport : public glove_transport {
public:
    explicit fake_transport(std::string name = "fake glove") : name_(std::move(name)) {}
    std::string name() const override { return name_; }
    void push(std::vector<std::uint8_t> bytes, double host_time) { q_.push_back({event::report, {std::move(bytes), host_time, 0}}); }
    /// A text line (a report of a line protocol), without its line end.
    void push_line(std::string_view line, double host_time) { push({line.begin(), line.end()}, host_time); }
    void push_timeout() { q_.push_back({event::timeout, {}}); }
    /// The next read after the queued events throws device_error; `failed_reconnects` attempts fail first.
    void push_disconnect(int failed_reconnects = 0) { q_.push_back({event::disconnect, {}}), fail_reconnects_ = failed_reconnects; }
    void close() { closed_ = true; }
    std::optional<hid_report> read(std::chrono::milliseconds) override
    {
        if (disconnected_) throw device_error("glove: " + name_ + " is disconnected");
        if (q_.empty()) return std::nullopt;
        auto e = std::move(q_.front());
        q_.pop_front();
        switch (e.kind) {
        case event::report: return std::move(e.report);
        case event::timeout: return std::nullopt;
        default: disconnected_ = true; throw device_error("glove: " + name_ + " disconnected");
        }
    }
    bool reconnect() override
    {
        ++reconnect_attempts;
        if (fail_reconnects_ > 0) return --fail_reconnects_, false;
        disconnected_ = false;
        return true;
    }
    bool finished() const override { return closed_ && q_.empty(); }
    void send_feature(std::span<const std::uint8_t> b) override { features_sent.emplace_back(b.begin(), b.end()); }
    void write(std::span<const std::uint8_t> b) override { written.emplace_back(b.begin(), b.end()); }
    std::vector<std::vector<std::uint8_t>> features_sent, written;
    int reconnect_attempts = 0;

private:
    enum class event { report, timeout, disconnect };
    struct item {
        event kind;
        hid_report report;
    };
    std::string name_;
    std::deque<item> q_;
    bool disconnected_ = false, closed_ = false;
    int fail_reconnects_ = 0;
};

}  // namespace handemo
