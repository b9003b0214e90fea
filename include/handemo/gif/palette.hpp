// The colour table of an animated GIF: GIF frames hold at most 256 colours and handemo's renderer draws lit,
// anti-aliased figures (far more than 256 shades per frame), so the colours are quantised. One global palette
// serves every frame (no colour flicker between frames): a few colours given by the caller are kept exact
// (the renderer's flat colours: background, grid, text), the rest of the table is fitted by median cut
// (Heckbert 1982) to the histogram of every frame's pixels: the box of colours with the largest
// count-weighted squared error is split at its weighted median along its widest-variance axis until the
// table is full, and each box contributes its count-weighted mean. With no more distinct colours than
// slots every colour is kept exactly. Pixels map to the nearest entry in squared RGB distance (no
// dithering: dithering noise changes from frame to frame and costs GIF compression).
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/image/rgb_image.hpp>

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <unordered_map>
#include <vector>

namespace handemo {

using rgb8 = std::array<std::uint8_t, 3>;

/// @brief Counts of the distinct colours of any number of images.
class colour_histogram {
public:
    /// @brief Adds every pixel of `im`.
    void add(const rgb_image& im)
    {
        im.validate("colour_histogram");
        for (std::size_t i = 0; i < im.pixels.size(); i += 3)
            ++counts_[key(im.pixels[i], im.pixels[i + 1], im.pixels[i + 2])];
    }
    std::size_t distinct() const noexcept { return counts_.size(); }
    const std::unordered_map<std::uint32_t, std::uint64_t>& counts() const noexcept { return counts_; }

    static constexpr std::uint32_t key(std::uint8_t r, std::uint8_t g, std::uint8_t b) noexcept
    {
        return (std::uint32_t{r} << 16) | (std::uint32_t{g} << 8) | b;
    }
    static constexpr rgb8 unkey(std::uint32_t k) noexcept
    {
        return {static_cast<std::uint8_t>(k >> 16), static_cast<std::uint8_t>(k >> 8), static_cast<std::uint8_t>(k)};
    }

private:
    std::unordered_map<std::uint32_t, std::uint64_t> counts_;
};

/// @brief A colour table of 1..256 entries; the first `reserved` entries are the caller's exact colours.
struct gif_palette {
    std::vector<rgb8> colors;
    std::size_t reserved = 0;

    /// @brief Index of the entry nearest to (r, g, b) in squared RGB distance (the first on ties).
    std::uint8_t nearest(std::uint8_t r, std::uint8_t g, std::uint8_t b) const noexcept
    {
        int best = std::numeric_limits<int>::max();
        std::size_t bi = 0;
        for (std::size_t i = 0; i < colors.size(); ++i) {
            const int dr = int{colors[i][0]} - r, dg = int{colors[i][1]} - g, db = int{colors[i][2]} - b;
            const int d = dr * dr + dg * dg + db * db;
            if (d < best) best = d, bi = i;
            if (d == 0) break;
        }
        return static_cast<std::uint8_t>(bi);
    }
};

/// @brief Maps pixels to palette indices, remembering the answer for each colour seen.
class palette_mapper {
public:
    explicit palette_mapper(const gif_palette& p) : p_(&p) {}
    std::uint8_t operator()(std::uint8_t r, std::uint8_t g, std::uint8_t b)
    {
        const auto k = colour_histogram::key(r, g, b);
        if (auto it = cache_.find(k); it != cache_.end()) return it->second;
        return cache_[k] = p_->nearest(r, g, b);
    }

private:
    const gif_palette* p_;
    std::unordered_map<std::uint32_t, std::uint8_t> cache_;
};

/// @brief A palette of at most `size` entries: `reserved` first (exact, duplicates dropped), then median
/// cut over the histogram's other colours (see the file comment).
/// @throws value_error when size is not in 1..256 or there are more reserved colours than size.
inline gif_palette median_cut_palette(const colour_histogram& hist, std::span<const rgb8> reserved, std::size_t size = 256)
{
    const std::string fn = "median_cut_palette";
    if (size < 1 || size > 256) throw value_error(fn + ": size " + std::to_string(size) + " is not in 1..256");
    gif_palette pal;
    std::vector<std::uint32_t> reserved_keys;
    for (const auto& c : reserved) {
        const auto k = colour_histogram::key(c[0], c[1], c[2]);
        if (std::find(reserved_keys.begin(), reserved_keys.end(), k) != reserved_keys.end()) continue;
        reserved_keys.push_back(k);
        pal.colors.push_back(c);
    }
    if (pal.colors.size() > size)
        throw value_error(fn + ": " + std::to_string(pal.colors.size()) + " reserved colours for a palette of " +
                          std::to_string(size));
    pal.reserved = pal.colors.size();
    struct item {
        std::array<int, 3> c;
        double n;
    };
    std::vector<item> items;
    for (const auto& [k, n] : hist.counts())
        if (std::find(reserved_keys.begin(), reserved_keys.end(), k) == reserved_keys.end()) {
            const rgb8 c = colour_histogram::unkey(k);
            items.push_back({{c[0], c[1], c[2]}, static_cast<double>(n)});
        }
    std::sort(items.begin(), items.end(), [](const item& a, const item& b) { return a.c < b.c; });  // deterministic
    const std::size_t slots = size - pal.colors.size();
    if (items.size() <= slots) {
        for (const auto& it : items)
            pal.colors.push_back({static_cast<std::uint8_t>(it.c[0]), static_cast<std::uint8_t>(it.c[1]), static_cast<std::uint8_t>(it.c[2])});
        if (pal.colors.empty()) pal.colors.push_back({0, 0, 0});
        return pal;
    }
    struct box {
        std::size_t begin, end;  // [begin, end) of items
        std::array<double, 3> mean{}, var{};
        double sse = 0;
    };
    auto measure = [&](std::size_t b, std::size_t e) {
        box x{b, e};
        double n = 0;
        for (std::size_t i = b; i < e; ++i) {
            n += items[i].n;
            for (int a = 0; a < 3; ++a) x.mean[static_cast<std::size_t>(a)] += items[i].n * items[i].c[static_cast<std::size_t>(a)];
        }
        for (auto& m : x.mean) m /= n;
        for (std::size_t i = b; i < e; ++i)
            for (std::size_t a = 0; a < 3; ++a) {
                const double d = items[i].c[a] - x.mean[a];
                x.var[a] += items[i].n * d * d;
            }
        x.sse = x.var[0] + x.var[1] + x.var[2];
        return x;
    };
    std::vector<box> boxes{measure(0, items.size())};
    while (boxes.size() < slots) {
        std::size_t bi = 0;
        for (std::size_t i = 1; i < boxes.size(); ++i)
            if (boxes[i].sse > boxes[bi].sse) bi = i;
        const box b = boxes[bi];
        if (b.end - b.begin < 2 || !(b.sse > 0)) break;  // every box is one colour
        const std::size_t axis = static_cast<std::size_t>(std::max_element(b.var.begin(), b.var.end()) - b.var.begin());
        std::sort(items.begin() + static_cast<long>(b.begin), items.begin() + static_cast<long>(b.end),
                  [axis](const item& x, const item& y) { return x.c[axis] < y.c[axis] || (x.c[axis] == y.c[axis] && x.c < y.c); });
        double total = 0, acc = 0;
        for (std::size_t i = b.begin; i < b.end; ++i) total += items[i].n;
        std::size_t cut = b.begin + 1;
        for (std::size_t i = b.begin; i < b.end - 1; ++i) {
            acc += items[i].n;
            cut = i + 1;
            if (acc >= total / 2) break;
        }
        boxes[bi] = measure(b.begin, cut);
        boxes.push_back(measure(cut, b.end));
    }
    for (const auto& b : boxes) {
        rgb8 c;
        for (std::size_t a = 0; a < 3; ++a) c[a] = static_cast<std::uint8_t>(std::clamp(std::lround(b.mean[a]), 0L, 255L));
        pal.colors.push_back(c);
    }
    return pal;
}

}  // namespace handemo
