// Animated GIF output through Debian's giflib (EGif* streaming API): the only file of handemo that includes
// <gif_lib.h>, reached through <handemo/gif.hpp> and the CMake target handemo::gif, so the core never needs
// giflib. The file is GIF89a with one global palette (palette.hpp: exact background/grid/text colours plus
// a median-cut fit to the frames), a NETSCAPE2.0 application extension (loop forever, or play once) and one
// graphic control extension + image per frame. It is encoded in memory and written with write_file_atomic.
//
// Timing. GIF delays are whole hundredths of a second, so a frame rate whose period is not a whole number
// of centiseconds cannot be held exactly frame by frame. Frame k (shown at t_k = k / fps) gets the delay
// round(100 (k + 1) / fps) - round(100 k / fps) cs: each frame ends within 5 ms of its true time and the
// loop lasts exactly round(100 N / fps) cs (30 fps: 3, 3, 4, 3, 3, 4 ... cs, i.e. 30 frames per second
// on average). Rates above 50 fps are refused: browsers show delays under 2 cs as 10 cs.
//
// Size. With `optimise` (the default) frame k > 0 stores only the bounding box of the pixels whose palette
// index differs from frame k - 1, and inside it the unchanged pixels as the transparent index (the last
// palette slot, kept free for it); disposal is "do not dispose", so a decoder that composites the frames
// (every browser, giflib's users) shows exactly the full frames.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/core/io.hpp>
#include <handemo/gif/palette.hpp>
#include <handemo/image/rgb_image.hpp>
#include <handemo/render/animation.hpp>

#include <gif_lib.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace handemo {

/// @brief Options of write_gif.
struct gif_options {
    bool loop = true;       ///< NETSCAPE2.0 loop count 0 (forever); false: play once (loop count 1)
    bool optimise = true;   ///< frames after the first store only changed pixels (see the file comment)
};

/// @brief Per-frame GIF delays in centiseconds for `frames` frames at `fps`: round(100 (k+1)/fps) - round(100 k/fps).
/// @throws value_error when fps is not in (0, 50].
inline std::vector<int> gif_delays(std::size_t frames, double fps)
{
    if (!(fps > 0) || !(fps <= 50))
        throw value_error("gif_delays: fps " + std::to_string(fps) + " is not in (0, 50] (GIF delays are whole centiseconds, at least 2)");
    std::vector<int> d(frames);
    for (std::size_t k = 0; k < frames; ++k)
        d[k] = static_cast<int>(std::llround(100.0 * static_cast<double>(k + 1) / fps) - std::llround(100.0 * static_cast<double>(k) / fps));
    return d;
}

/// @brief Encodes frames into an animated GIF in memory (see the file comment for the layout).
class gif_encoder {
public:
    /// @param what names the output in error messages (the file name).
    /// @throws value_error for a zero or >65535 side or a palette of 0 or >256 colours (255 with optimise);
    ///         io_error when giflib fails.
    gif_encoder(std::size_t width, std::size_t height, gif_palette palette, gif_options opt = {}, std::string what = "gif")
        : w_(width), h_(height), pal_(std::move(palette)), opt_(opt), what_(std::move(what)), map_(pal_)
    {
        if (w_ == 0 || h_ == 0 || w_ > 65535 || h_ > 65535)
            throw value_error(what_ + ": GIF size " + std::to_string(w_) + "x" + std::to_string(h_) + " is not in 1..65535 per side");
        const std::size_t limit = opt_.optimise ? 255 : 256;
        if (pal_.colors.empty() || pal_.colors.size() > limit)
            throw value_error(what_ + ": palette of " + std::to_string(pal_.colors.size()) + " colours is not in 1.." + std::to_string(limit));
        transparent_ = opt_.optimise ? static_cast<int>(pal_.colors.size()) : -1;
        int err = 0;
        gif_ = EGifOpen(this, &gif_encoder::output, &err);
        if (!gif_) fail("EGifOpen", err);
        EGifSetGifVersion(gif_, true);
        const int table = 256;  // the table a GIF stores is a power of two; unused entries are black
        ColorMapObject* cm = GifMakeMapObject(table, nullptr);
        if (!cm) fail("GifMakeMapObject", D_GIF_ERR_NOT_ENOUGH_MEM);
        for (int i = 0; i < table; ++i) {
            const rgb8 c = static_cast<std::size_t>(i) < pal_.colors.size() ? pal_.colors[static_cast<std::size_t>(i)] : rgb8{0, 0, 0};
            cm->Colors[i] = GifColorType{c[0], c[1], c[2]};
        }
        const int rc = EGifPutScreenDesc(gif_, static_cast<int>(w_), static_cast<int>(h_), 8, 0, cm);
        GifFreeMapObject(cm);
        if (rc != GIF_OK) fail("EGifPutScreenDesc", gif_->Error);
        // NETSCAPE2.0: sub-block 1, loop count (little endian) 0 = forever
        unsigned char app[] = {'N', 'E', 'T', 'S', 'C', 'A', 'P', 'E', '2', '.', '0'};
        unsigned char loop[] = {1, static_cast<unsigned char>(opt_.loop ? 0 : 1), 0};
        if (EGifPutExtensionLeader(gif_, APPLICATION_EXT_FUNC_CODE) != GIF_OK || EGifPutExtensionBlock(gif_, 11, app) != GIF_OK ||
            EGifPutExtensionBlock(gif_, 3, loop) != GIF_OK || EGifPutExtensionTrailer(gif_) != GIF_OK)
            fail("EGifPutExtension (NETSCAPE2.0)", gif_->Error);
    }
    gif_encoder(const gif_encoder&) = delete;
    gif_encoder& operator=(const gif_encoder&) = delete;
    ~gif_encoder()
    {
        if (gif_) {
            int err = 0;
            EGifCloseFile(gif_, &err);
        }
    }

    /// @brief Appends a frame shown for `delay_cs` hundredths of a second.
    /// @throws shape_error when the frame's size is not the GIF's; value_error for a delay not in 0..65535;
    ///         io_error when giflib fails.
    void add_frame(const rgb_image& im, int delay_cs)
    {
        im.validate(what_);
        if (im.width != w_ || im.height != h_)
            throw shape_error(what_ + ": frame " + std::to_string(frames_) + " is " + std::to_string(im.width) + "x" +
                              std::to_string(im.height) + ", expected " + std::to_string(w_) + "x" + std::to_string(h_));
        if (delay_cs < 0 || delay_cs > 65535) throw value_error(what_ + ": delay " + std::to_string(delay_cs) + " cs is not in 0..65535");
        std::vector<GifByteType> idx(w_ * h_);
        for (std::size_t i = 0; i < idx.size(); ++i) idx[i] = map_(im.pixels[3 * i], im.pixels[3 * i + 1], im.pixels[3 * i + 2]);
        std::size_t x0 = 0, y0 = 0, x1 = w_, y1 = h_;
        std::vector<GifByteType> out;
        const bool delta = opt_.optimise && !prev_.empty();
        if (delta) {
            x0 = w_, y0 = h_, x1 = 0, y1 = 0;
            for (std::size_t y = 0; y < h_; ++y)
                for (std::size_t x = 0; x < w_; ++x)
                    if (idx[y * w_ + x] != prev_[y * w_ + x])
                        x0 = std::min(x0, x), x1 = std::max(x1, x + 1), y0 = std::min(y0, y), y1 = std::max(y1, y + 1);
            if (x1 == 0) x0 = y0 = 0, x1 = y1 = 1;  // nothing changed: one transparent pixel
        }
        for (std::size_t y = y0; y < y1; ++y)
            for (std::size_t x = x0; x < x1; ++x) {
                const std::size_t i = y * w_ + x;
                out.push_back(delta && idx[i] == prev_[i] ? static_cast<GifByteType>(transparent_) : idx[i]);
            }
        GraphicsControlBlock gcb{};
        gcb.DisposalMode = DISPOSE_DO_NOT;
        gcb.UserInputFlag = false;
        gcb.DelayTime = delay_cs;
        gcb.TransparentColor = delta ? transparent_ : NO_TRANSPARENT_COLOR;
        GifByteType ext[4];
        const auto len = EGifGCBToExtension(&gcb, ext);
        if (EGifPutExtension(gif_, GRAPHICS_EXT_FUNC_CODE, static_cast<int>(len), ext) != GIF_OK)
            fail("EGifPutExtension (graphic control)", gif_->Error);
        const auto bw = static_cast<int>(x1 - x0);
        if (EGifPutImageDesc(gif_, static_cast<int>(x0), static_cast<int>(y0), bw, static_cast<int>(y1 - y0), false, nullptr) != GIF_OK)
            fail("EGifPutImageDesc", gif_->Error);
        for (std::size_t r = 0; r < y1 - y0; ++r)
            if (EGifPutLine(gif_, out.data() + r * static_cast<std::size_t>(bw), bw) != GIF_OK) fail("EGifPutLine", gif_->Error);
        prev_ = std::move(idx);
        ++frames_;
    }

    std::size_t frame_count() const noexcept { return frames_; }

    /// @brief Ends the stream and returns the GIF file's bytes.
    /// @throws value_error when no frame was added; io_error when giflib fails.
    std::string finish()
    {
        if (frames_ == 0) throw value_error(what_ + ": no frames to write (expected at least one)");
        int err = 0;
        GifFileType* g = gif_;
        gif_ = nullptr;
        if (EGifCloseFile(g, &err) != GIF_OK) fail("EGifCloseFile", err);
        return std::move(bytes_);
    }

private:
    static int output(GifFileType* g, const GifByteType* data, int n)
    {
        auto* self = static_cast<gif_encoder*>(g->UserData);
        self->bytes_.append(reinterpret_cast<const char*>(data), static_cast<std::size_t>(n));
        return n;
    }
    [[noreturn]] void fail(const char* call, int code) const
    {
        const char* msg = GifErrorString(code);
        throw io_error(what_ + ": giflib " + call + " failed: " + (msg ? msg : "error " + std::to_string(code)));
    }

    std::size_t w_, h_;
    gif_palette pal_;
    gif_options opt_;
    std::string what_;
    palette_mapper map_;
    int transparent_ = -1;
    GifFileType* gif_ = nullptr;
    std::string bytes_;
    std::vector<GifByteType> prev_;
    std::size_t frames_ = 0;
};

/// @brief The palette write_gif uses for an animation: the renderer's flat colours (figure background,
/// filmstrip grid, title ink, frame-label grey) exact, the rest median cut over every frame's pixels.
inline gif_palette animation_palette(const filmstrip_animation& anim, std::size_t size = 255)
{
    colour_histogram hist;
    for (std::size_t k = 0; k < anim.frame_count(); ++k) hist.add(anim.frame(k));
    auto to8 = [](color c) {
        return rgb8{static_cast<std::uint8_t>(std::lround(std::clamp(c.r, 0.0f, 1.0f) * 255.0f)),
                    static_cast<std::uint8_t>(std::lround(std::clamp(c.g, 0.0f, 1.0f) * 255.0f)),
                    static_cast<std::uint8_t>(std::lround(std::clamp(c.b, 0.0f, 1.0f) * 255.0f))};
    };
    const auto& s = anim.options().strip;
    const std::vector<rgb8> reserved{to8(s.figure.background), to8(s.grid_color), to8(color::rgb8(30, 30, 30)),
                                     to8(color::rgb8(140, 140, 140))};
    return median_cut_palette(hist, reserved, size);
}

/// @brief Writes a filmstrip animation as an animated GIF, atomically: every output frame of `anim`, with
/// the delays of gif_delays(anim.frame_count(), anim.fps()).
/// @return the number of bytes written.
/// @throws value_error naming the file when the rate is above 50 fps; io_error naming the file when it
///         cannot be written or giflib fails.
inline std::size_t write_gif(const std::filesystem::path& path, const filmstrip_animation& anim, const gif_options& opt = {})
{
    const std::string what = "write_gif: " + path.string();
    if (!(anim.fps() <= 50))
        throw value_error(what + ": " + std::to_string(anim.fps()) + " fps is above 50 (GIF delays are whole centiseconds, at least 2)");
    const auto delays = gif_delays(anim.frame_count(), anim.fps());
    gif_palette pal = animation_palette(anim, opt.optimise ? 255 : 256);
    const rgb_image first = anim.frame(0);
    gif_encoder enc(first.width, first.height, std::move(pal), opt, what);
    enc.add_frame(first, delays[0]);
    for (std::size_t k = 1; k < anim.frame_count(); ++k) enc.add_frame(anim.frame(k), delays[k]);
    const std::string bytes = enc.finish();
    write_file_atomic(path, bytes);
    return bytes.size();
}

}  // namespace handemo
