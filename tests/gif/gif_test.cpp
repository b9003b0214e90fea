// Tests of animated GIF output (gif/palette.hpp, gif/writer.hpp; the animation's timing is tested in
// tests/render/animation_test.cpp): the written file is decoded with giflib (DGifOpenFileName + DGifSlurp) and its
// frame count, size, loop extension, delays and composited pixels are checked against the PNG renderer.
#include "helpers.hpp"

#include <handemo/gif.hpp>
#include <handemo/image.hpp>
#include <handemo/render.hpp>

#include <doctest/doctest.h>

#include <gif_lib.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <memory>
#include <numeric>
#include <string>
#include <vector>

#include <unistd.h>

using namespace handemo;
namespace fs = std::filesystem;

namespace {

fs::path temp_dir(const std::string& name)
{
    const fs::path d = fs::temp_directory_path() / ("handemo_gif_" + name + "_" + std::to_string(::getpid()));
    fs::remove_all(d);
    fs::create_directories(d);
    return d;
}

/// A decoded GIF: every frame composited onto the logical screen (disposal "do not dispose", transparency
/// honoured), as a browser shows it, plus the delays and the NETSCAPE2.0 loop count (-1 when absent).
struct decoded_gif {
    std::size_t width = 0, height = 0;
    std::vector<rgb_image> frames;
    std::vector<int> delays;
    int loop_count = -1;
    int colours = 0;
};

decoded_gif decode(const fs::path& path)
{
    int err = 0;
    GifFileType* g = DGifOpenFileName(path.string().c_str(), &err);
    REQUIRE_MESSAGE(g != nullptr, GifErrorString(err));
    std::unique_ptr<GifFileType, void (*)(GifFileType*)> guard(g, [](GifFileType* p) {
        int e = 0;
        DGifCloseFile(p, &e);
    });
    REQUIRE(DGifSlurp(g) == GIF_OK);
    decoded_gif d;
    d.width = static_cast<std::size_t>(g->SWidth);
    d.height = static_cast<std::size_t>(g->SHeight);
    REQUIRE(g->SColorMap != nullptr);
    d.colours = g->SColorMap->ColorCount;
    std::vector<int> screen(d.width * d.height, 0);
    for (int i = 0; i < g->ImageCount; ++i) {
        const SavedImage& im = g->SavedImages[i];
        for (int e = 0; e + 1 < im.ExtensionBlockCount; ++e) {
            const ExtensionBlock& b = im.ExtensionBlocks[e];
            if (b.Function == APPLICATION_EXT_FUNC_CODE && b.ByteCount == 11 && std::memcmp(b.Bytes, "NETSCAPE2.0", 11) == 0) {
                const ExtensionBlock& s = im.ExtensionBlocks[e + 1];
                REQUIRE(s.Function == CONTINUE_EXT_FUNC_CODE);
                REQUIRE(s.ByteCount == 3);
                CHECK(s.Bytes[0] == 1);
                d.loop_count = s.Bytes[1] | (s.Bytes[2] << 8);
            }
        }
        GraphicsControlBlock gcb{};
        REQUIRE(DGifSavedExtensionToGCB(g, i, &gcb) == GIF_OK);
        CHECK(gcb.DisposalMode == DISPOSE_DO_NOT);
        d.delays.push_back(gcb.DelayTime);
        const GifImageDesc& desc = im.ImageDesc;
        REQUIRE(desc.Left + desc.Width <= g->SWidth);
        REQUIRE(desc.Top + desc.Height <= g->SHeight);
        CHECK_FALSE(desc.Interlace);
        for (int y = 0; y < desc.Height; ++y)
            for (int x = 0; x < desc.Width; ++x) {
                const int v = im.RasterBits[y * desc.Width + x];
                if (v == gcb.TransparentColor) continue;
                screen[static_cast<std::size_t>(desc.Top + y) * d.width + static_cast<std::size_t>(desc.Left + x)] = v;
            }
        rgb_image out = rgb_image::make(d.width, d.height);
        for (std::size_t p = 0; p < screen.size(); ++p) {
            const GifColorType c = g->SColorMap->Colors[screen[p]];
            out.pixels[3 * p] = c.Red, out.pixels[3 * p + 1] = c.Green, out.pixels[3 * p + 2] = c.Blue;
        }
        d.frames.push_back(std::move(out));
    }
    return d;
}

struct pixel_error {
    int max = 0;
    double mean = 0;          ///< mean absolute channel difference
    std::size_t flat_wrong = 0;  ///< pixels of a reserved (flat) colour that differ
};

pixel_error compare(const rgb_image& a, const rgb_image& b, const std::vector<rgb8>& flat)
{
    REQUIRE(a.width == b.width);
    REQUIRE(a.height == b.height);
    pixel_error e;
    double sum = 0;
    for (std::size_t p = 0; p < a.width * a.height; ++p) {
        const rgb8 ca{a.pixels[3 * p], a.pixels[3 * p + 1], a.pixels[3 * p + 2]};
        int m = 0;
        for (std::size_t k = 0; k < 3; ++k) {
            const int d = std::abs(int{ca[k]} - int{b.pixels[3 * p + k]});
            m = std::max(m, d);
            sum += d;
        }
        e.max = std::max(e.max, m);
        if (m > 0 && std::find(flat.begin(), flat.end(), ca) != flat.end()) ++e.flat_wrong;
    }
    e.mean = sum / static_cast<double>(a.pixels.size());
    return e;
}

animation_options two_clip_options()
{
    animation_options o;
    o.strip.cell_width = o.strip.cell_height = 120;
    o.strip.titles = {"hand", "body"};
    return o;
}

const std::vector<rgb8> flat_colours{{255, 255, 255}, {215, 215, 215}, {30, 30, 30}, {140, 140, 140}};

}  // namespace

TEST_CASE("gif: delays are whole centiseconds that add up to the true duration")
{
    const auto d30 = gif_delays(30, 30.0);
    CHECK(std::accumulate(d30.begin(), d30.end(), 0) == 100);
    for (int v : d30) CHECK((v == 3 || v == 4));
    for (std::size_t k = 0; k < 30; ++k) {  // frame k ends within half a centisecond of (k + 1) / fps
        const int end = std::accumulate(d30.begin(), d30.begin() + static_cast<long>(k) + 1, 0);
        CHECK(std::abs(end - 100.0 * static_cast<double>(k + 1) / 30.0) <= 0.5);
    }
    const auto d25 = gif_delays(10, 25.0);
    CHECK(std::all_of(d25.begin(), d25.end(), [](int v) { return v == 4; }));
    const auto d12 = gif_delays(24, 12.0);  // 8.33 cs: 8, 9, 8, 8, 9, 8, ...
    CHECK(std::accumulate(d12.begin(), d12.end(), 0) == 200);
    CHECK_THROWS_AS(gif_delays(3, 60.0), value_error);
    CHECK_THROWS_AS(gif_delays(3, 0.0), value_error);
}

TEST_CASE("gif: median cut keeps reserved colours first and exact, and every colour when they fit")
{
    rgb_image im = rgb_image::make(4, 1);
    const std::vector<rgb8> px{{10, 20, 30}, {200, 0, 0}, {200, 0, 0}, {0, 0, 255}};
    for (std::size_t i = 0; i < 4; ++i) std::copy(px[i].begin(), px[i].end(), im.pixels.begin() + static_cast<long>(3 * i));
    colour_histogram h;
    h.add(im);
    CHECK(h.distinct() == 3);
    const std::vector<rgb8> reserved{{255, 255, 255}, {0, 0, 255}, {255, 255, 255}};
    const gif_palette p = median_cut_palette(h, reserved, 8);
    CHECK(p.reserved == 2);
    REQUIRE(p.colors.size() == 4);
    CHECK(p.colors[0] == rgb8{255, 255, 255});
    CHECK(p.colors[1] == rgb8{0, 0, 255});
    for (const auto& c : px) CHECK(p.colors[p.nearest(c[0], c[1], c[2])] == c);
    // more colours than slots: a gradient of 256 greys into 16 entries, each within half a bucket
    rgb_image g = rgb_image::make(256, 1);
    for (std::size_t i = 0; i < 256; ++i) g.pixels[3 * i] = g.pixels[3 * i + 1] = g.pixels[3 * i + 2] = static_cast<std::uint8_t>(i);
    colour_histogram hg;
    hg.add(g);
    const gif_palette q = median_cut_palette(hg, {}, 16);
    CHECK(q.colors.size() == 16);
    for (int v = 0; v < 256; ++v) {
        const auto u = static_cast<std::uint8_t>(v);
        CHECK(std::abs(int{q.colors[q.nearest(u, u, u)][0]} - v) <= 8);
    }
    CHECK_THROWS_AS(median_cut_palette(hg, {}, 0), value_error);
    CHECK_THROWS_AS(median_cut_palette(hg, reserved, 1), value_error);
}

TEST_CASE("gif: the written GIF decodes to the PNG renderer's frames")
{
    const std::vector<clip> clips{test::flexing_hand(40), test::stick_body(20)};
    const filmstrip_animation a(clips, two_clip_options());
    colour_histogram hist;  // more colours than a GIF holds, so the palette really is quantised here
    for (std::size_t k = 0; k < a.frame_count(); ++k) hist.add(a.frame(k));
    MESSAGE(hist.distinct() << " distinct colours in " << a.frame_count() << " frames");
    CHECK(hist.distinct() > 1000);
    const fs::path dir = temp_dir("write");
    for (const bool optimise : {true, false}) {
        CAPTURE(optimise);
        const fs::path path = dir / (optimise ? "anim.gif" : "anim_full.gif");
        const std::size_t bytes = write_gif(path, a, {true, optimise});
        CHECK(fs::file_size(path) == bytes);
        const decoded_gif d = decode(path);
        const rgb_image f0 = a.frame(0);
        CHECK(d.width == f0.width);
        CHECK(d.height == f0.height);
        REQUIRE(d.frames.size() == a.frame_count());
        CHECK(d.loop_count == 0);
        CHECK(d.delays == gif_delays(a.frame_count(), a.fps()));
        CHECK(d.colours == 256);
        // Every frame against the PNG renderer: flat colours exact, shaded pixels quantised to <= 255 colours.
        double worst_mean = 0;
        int worst_max = 0;
        for (std::size_t k = 0; k < a.frame_count(); ++k) {
            const pixel_error e = compare(a.frame(k), d.frames[k], flat_colours);
            CHECK(e.flat_wrong == 0);
            worst_mean = std::max(worst_mean, e.mean);
            worst_max = std::max(worst_max, e.max);
        }
        MESSAGE("largest channel error " << worst_max << ", largest per-frame mean " << worst_mean << ", " << bytes << " bytes");
        CHECK(worst_mean <= 0.5);
        CHECK(worst_max <= 48);
        // Frame 20 (t = 20/30 s) against the PNG file of the one-row filmstrip of the same frames.
        filmstrip_options fo = two_clip_options().strip;
        const auto fr = a.clip_frames(20);
        const rgb_image png_frame = detail::draw_filmstrip(clips, fo, plan_filmstrip(clips, [&] { auto x = fo; x.rows = 1; return x; }()), 1,
                                                           [&](std::size_t, std::size_t c) { return fr[c]; });
        write_png(dir / "frame20.png", png_frame);
        const pixel_error e20 = compare(read_image(dir / "frame20.png"), d.frames[20], flat_colours);
        CHECK(e20.flat_wrong == 0);
        CHECK(e20.mean <= 0.5);
    }
    fs::remove_all(dir);
}

TEST_CASE("gif: play once, and errors name the file")
{
    const std::vector<clip> clips{test::flexing_hand(6)};
    animation_options o;
    o.strip.cell_width = o.strip.cell_height = 48;
    const filmstrip_animation a(clips, o);
    const fs::path dir = temp_dir("errors");
    write_gif(dir / "once.gif", a, {false, true});
    CHECK(decode(dir / "once.gif").loop_count == 1);
    // a path below a regular file cannot be created
    write_file_atomic(dir / "file.txt", "x");
    CHECK_THROWS_WITH_AS(write_gif(dir / "file.txt" / "out.gif", a), doctest::Contains("out.gif"), io_error);
    o.fps = 60;
    CHECK_THROWS_WITH_AS(write_gif(dir / "fast.gif", filmstrip_animation(clips, o)), doctest::Contains("fast.gif"), value_error);
    CHECK_FALSE(fs::exists(dir / "fast.gif"));
    fs::remove_all(dir);
}
