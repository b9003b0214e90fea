// Fuzz target: the glove's outside bytes. Input starting with '{' is a device profile (parse_glove_profile);
// input starting with "HGLVRAW1" a recorded raw stream (parse_raw_stream, `handemo glove record --raw`)
// whose reports are decoded with recorded times; anything else is a stream of HID reports (one length byte,
// then that many bytes, repeated). Reports are decoded with both example profiles of examples/glove/.
#include "fuzz.hpp"

#include <handemo/glove/profile.hpp>
#include <handemo/glove/transport.hpp>

#include <memory>
#include <vector>

namespace handemo_fuzz::glove {

inline const std::vector<handemo::glove_profile>& profiles()
{
    static const std::vector<handemo::glove_profile> p = {
        handemo::read_glove_profile(HANDEMO_SOURCE_DIR "/examples/glove/imu7_example.json"),
        handemo::read_glove_profile(HANDEMO_SOURCE_DIR "/examples/glove/flex15_example.json")};
    return p;
}

inline void decode_stream(const handemo::glove_profile& p, std::string_view bytes)
{
    handemo::report_decoder dec(p);
    handemo::glove_sample s;
    double t = 0;
    std::size_t at = 0;
    while (at < bytes.size()) {
        const std::size_t n = std::min<std::size_t>(static_cast<unsigned char>(bytes[at]), bytes.size() - at - 1);
        const auto* b = reinterpret_cast<const std::uint8_t*>(bytes.data() + at + 1);
        (void)dec.decode(std::span<const std::uint8_t>(b, n), t, s);
        t += 0.01;
        at += 1 + n;
    }
}

inline int run(const std::uint8_t* data, std::size_t size)
{
    const std::string_view text = as_text(data, size);
    return refuse_ok([&] {
        if (text.starts_with("HGLVRAW1")) {
            long truncated = -1;
            const auto reports = handemo::parse_raw_stream(text, "fuzz.raw", truncated);
            for (const auto& p : profiles()) {
                handemo::report_decoder dec(p);
                handemo::glove_sample s;
                for (const auto& r : reports) (void)dec.decode(r.bytes, r.host_time, s);
            }
        } else if (!text.empty() && text.front() == '{') {
            const handemo::glove_profile p = handemo::parse_glove_profile(text, "fuzz-profile.json");
            decode_stream(p, std::string_view("\x40\x01\x02\x03\x04\x05\x06\x07\x08", 9));
        } else {
            for (const auto& p : profiles()) decode_stream(p, text);
        }
    });
}

}  // namespace handemo_fuzz::glove

HANDEMO_FUZZ_ENTRY(glove)
