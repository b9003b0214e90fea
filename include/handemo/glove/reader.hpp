// The reader thread: a transport read on a thread of its own, which stamps every report with its arrival
// time and puts it in a bounded queue, so a consumer that is busy (a transfer in `glove live`, a slow disk)
// does not squeeze the reports it has not read yet together in time. The consumer reads the queue through
// the same glove_transport interface. When the queue is full the oldest report is dropped and counted
// (overruns()): nothing is lost without a count. A disconnect reaches the consumer in order, after the
// reports read before it, as the device_error it was; the thread tries to reopen the device within the
// reconnect window and tells the consumer's reconnect() how that went.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/glove/transport.hpp>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

namespace handemo {

/// @brief Options of a glove_reader.
struct reader_options {
    std::size_t capacity = 4096;                     ///< reports held before the oldest is dropped
    std::chrono::milliseconds poll{20};              ///< the thread's read timeout (how soon it sees stop())
    double reconnect_window = 0;                     ///< seconds to try to reopen after a disconnect (0: give up)
    double reconnect_poll = 0.2;                     ///< seconds between attempts
};

/// @brief Reads a transport on its own thread into a bounded queue (see the file comment).
class glove_reader : public glove_transport {
public:
    /// Starts the thread at once.
    explicit glove_reader(std::unique_ptr<glove_transport> inner, reader_options o = {}) : inner_(std::move(inner)), o_(o)
    {
        if (o_.capacity == 0) throw value_error("glove_reader: capacity 0");
        name_ = inner_->name();
        thread_ = std::thread([this] { run(); });
    }
    glove_reader(const glove_reader&) = delete;
    glove_reader& operator=(const glove_reader&) = delete;
    ~glove_reader() override { stop(); }

    std::string name() const override { return name_; }

    /// @brief The oldest queued report, waiting up to `timeout`.
    /// @throws device_error (the transport's own) where the device disconnected.
    std::optional<hid_report> read(std::chrono::milliseconds timeout) override
    {
        std::unique_lock lock(m_);
        if (!cv_.wait_for(lock, timeout, [&] { return !q_.empty(); })) return std::nullopt;
        item it = std::move(q_.front());
        q_.pop_front();
        switch (it.kind) {
        case event::report: --reports_queued_; return std::move(it.report);
        case event::finished: finished_ = true; return std::nullopt;
        case event::disconnect: throw device_error(it.message);
        default: return std::nullopt;  // a reconnect outcome nobody waited for
        }
    }

    /// @brief Waits up to the reconnect poll for the thread's attempt to reopen the device.
    /// @return true once it has reopened it; false while it is still trying or after it gave up.
    bool reconnect() override
    {
        std::unique_lock lock(m_);
        const auto wait = std::chrono::duration<double>(o_.reconnect_poll);
        cv_.wait_for(lock, wait, [&] { return !q_.empty() && (q_.front().kind == event::reconnected || q_.front().kind == event::gave_up); });
        if (q_.empty()) return false;
        if (q_.front().kind == event::reconnected) return q_.pop_front(), true;
        if (q_.front().kind == event::gave_up) gave_up_ = true, q_.pop_front();
        return false;
    }
    bool finished() const override
    {
        std::lock_guard lock(m_);
        return finished_ || (gave_up_ && q_.empty());
    }
    /// @brief Sends to the device: the thread writes it between two reads, and this waits until it has.
    /// @throws device_error naming the device when the write fails or the thread has ended.
    void write(std::span<const std::uint8_t> b) override
    {
        std::unique_lock lock(m_);
        const std::uint64_t ticket = ++write_posted_;
        out_.emplace_back(b.begin(), b.end());
        if (!cv_.wait_for(lock, std::chrono::seconds(2), [&] { return write_done_ >= ticket || ended_; }) || write_done_ < ticket)
            throw device_error("glove: " + name_ + ": the reader thread did not send the command (" + (ended_ ? "it has ended" : "timeout") + ")");
        if (!write_error_.empty()) {
            std::string e;
            std::swap(e, write_error_);
            throw device_error(e);
        }
    }
    std::size_t overruns() const override { return overruns_.load(); }
    /// Reports the thread has put in the queue.
    std::size_t received() const noexcept { return received_.load(); }
    /// Reports in the queue now.
    std::size_t queued() const
    {
        std::lock_guard lock(m_);
        return reports_queued_;
    }
    /// @brief Ends the thread (also done by the destructor). Queued reports can still be read.
    void stop()
    {
        stop_.store(true);
        if (thread_.joinable()) thread_.join();
    }

private:
    enum class event : std::uint8_t { report, disconnect, reconnected, gave_up, finished };
    struct item {
        event kind;
        hid_report report;
        std::string message;
    };
    void push(item it)
    {
        {
            std::lock_guard lock(m_);
            if (it.kind == event::report) {
                if (reports_queued_ == o_.capacity) {
                    for (auto i = q_.begin(); i != q_.end(); ++i)
                        if (i->kind == event::report) {
                            q_.erase(i);
                            break;
                        }
                    --reports_queued_;
                    overruns_.fetch_add(1);
                }
                ++reports_queued_;
                received_.fetch_add(1);
            }
            q_.push_back(std::move(it));
        }
        cv_.notify_all();
    }
    /// Sends the commands write() posted (on the thread, between reads).
    void send_pending()
    {
        std::vector<std::vector<std::uint8_t>> out;
        {
            std::lock_guard lock(m_);
            if (out_.empty()) return;
            out.swap(out_);
        }
        std::string error;
        for (const auto& b : out) try {
                inner_->write(b);
            } catch (const device_error& e) {
                error = e.what();
            }
        {
            std::lock_guard lock(m_);
            write_done_ += out.size();
            if (!error.empty()) write_error_ = error;
        }
        cv_.notify_all();
    }
    void run()
    {
        run_loop();
        std::lock_guard lock(m_);
        ended_ = true;
        cv_.notify_all();
    }
    void run_loop()
    {
        while (!stop_.load()) {
            try {
                send_pending();
                std::optional<hid_report> r = inner_->read(o_.poll);
                const bool done = !r && inner_->finished();
                if (r) {
                    r->arrival = host_seconds();
                    push({event::report, std::move(*r), {}});
                } else if (done) {
                    push({event::finished, {}, {}});
                    return;
                }
            } catch (const device_error& e) {
                push({event::disconnect, {}, e.what()});
                const double start = host_seconds();
                bool ok = false;
                while (!stop_.load() && !ok) {
                    ok = inner_->reconnect();
                    if (ok || host_seconds() - start >= o_.reconnect_window) break;
                    std::this_thread::sleep_for(std::chrono::duration<double>(std::min(o_.reconnect_poll, 0.05)));
                }
                push({ok ? event::reconnected : event::gave_up, {}, {}});
                if (!ok) return;
            }
        }
    }

    std::unique_ptr<glove_transport> inner_;
    reader_options o_;
    std::string name_;
    mutable std::mutex m_;
    std::condition_variable cv_;
    std::deque<item> q_;
    std::vector<std::vector<std::uint8_t>> out_;
    std::uint64_t write_posted_ = 0, write_done_ = 0;
    std::string write_error_;
    std::size_t reports_queued_ = 0;
    bool finished_ = false, gave_up_ = false, ended_ = false;
    std::atomic<std::size_t> overruns_{0}, received_{0};
    std::atomic<bool> stop_{false};
    std::thread thread_;
};

}  // namespace handemo
