// A tiny software rasteriser for handemo's pictures (the filmstrips of the hand paper's Figures 4-12 and
// the motion-image views of Figure 3): a floating-point RGB canvas with anti-aliased primitives drawn by
// signed-distance coverage. A pixel (x, y) covers [x, x+1) x [y, y+1) and is sampled at its centre; the
// coverage of a shape whose signed distance at the centre is d (negative inside) is clamp(0.5 - d, 0, 1),
// which is exact for a straight edge crossing the pixel perpendicular to an axis and a good approximation
// otherwise. Bones are capsules (segments with radii r0 -> r1) lit as cylinders, joints are lit spheres:
// the surface normal at a covered pixel is n = ((p - c) / r, sqrt(1 - |p - c|^2 / r^2)), c the closest
// point on the axis, shaded with one directional light (Lambert + Blinn-Phong).
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/image/rgb_image.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace handemo {

/// @brief A linear RGB colour with components in [0, 1].
struct color {
    float r = 0, g = 0, b = 0;

    /// @brief A colour from 8-bit components.
    static constexpr color rgb8(int r8, int g8, int b8) noexcept
    {
        return {static_cast<float>(r8) / 255.0f, static_cast<float>(g8) / 255.0f, static_cast<float>(b8) / 255.0f};
    }
    /// @brief Linear interpolation `a + t (b - a)`.
    friend constexpr color mix(color a, color b, float t) noexcept
    {
        return {a.r + t * (b.r - a.r), a.g + t * (b.g - a.g), a.b + t * (b.b - a.b)};
    }
    friend constexpr color scale(color a, float s) noexcept { return {a.r * s, a.g * s, a.b * s}; }
    friend constexpr bool operator==(color, color) = default;
};

/// A point on the canvas in pixels (x right, y down).
struct point2 {
    double x = 0, y = 0;
};

/// @brief A width x height floating-point RGB image that primitives are blended into.
class canvas {
public:
    canvas() = default;
    /// @brief A canvas filled with `background`.
    /// @throws value_error when a side is zero or the canvas would exceed 2^26 pixels.
    canvas(std::size_t width, std::size_t height, color background = {1, 1, 1})
        : width_(width), height_(height)
    {
        if (width == 0 || height == 0 || width > (1u << 15) || height > (1u << 15) || width * height > (1u << 26))
            throw value_error("canvas: size " + std::to_string(width) + "x" + std::to_string(height) +
                              " is not in 1..32768 per side and at most 2^26 pixels");
        data_.resize(width * height * 3);
        for (std::size_t i = 0; i < width * height; ++i) {
            data_[i * 3] = background.r;
            data_[i * 3 + 1] = background.g;
            data_[i * 3 + 2] = background.b;
        }
    }

    std::size_t width() const noexcept { return width_; }
    std::size_t height() const noexcept { return height_; }
    /// Row-major [height, width, 3] floats.
    std::span<const float> data() const noexcept { return data_; }

    /// @brief The colour at (x, y); (0, 0, 0) outside the canvas.
    color at(std::size_t x, std::size_t y) const noexcept
    {
        if (x >= width_ || y >= height_) return {};
        const float* p = data_.data() + (y * width_ + x) * 3;
        return {p[0], p[1], p[2]};
    }

    /// @brief Blends `c` over pixel (x, y) with opacity `alpha`; ignores pixels outside the canvas.
    void blend(long x, long y, color c, float alpha) noexcept
    {
        if (x < 0 || y < 0 || x >= static_cast<long>(width_) || y >= static_cast<long>(height_) || !(alpha > 0)) return;
        alpha = std::min(alpha, 1.0f);
        float* p = data_.data() + (static_cast<std::size_t>(y) * width_ + static_cast<std::size_t>(x)) * 3;
        p[0] += alpha * (c.r - p[0]);
        p[1] += alpha * (c.g - p[1]);
        p[2] += alpha * (c.b - p[2]);
    }

    /// @brief Fills the pixel rectangle [x0, x1) x [y0, y1) (clipped) with `c`.
    void fill_rect(long x0, long y0, long x1, long y1, color c, float alpha = 1.0f) noexcept
    {
        x0 = std::max(x0, 0L);
        y0 = std::max(y0, 0L);
        x1 = std::min(x1, static_cast<long>(width_));
        y1 = std::min(y1, static_cast<long>(height_));
        for (long y = y0; y < y1; ++y)
            for (long x = x0; x < x1; ++x) blend(x, y, c, alpha);
    }

    /// @brief A flat anti-aliased line of the given width (a capsule without shading).
    void draw_line(point2 a, point2 b, double width, color c, float alpha = 1.0f) noexcept
    {
        shape_capsule(a, b, width / 2, width / 2, c, alpha, false);
    }

    /// @brief A lit capsule from `a` (radius `r0`) to `b` (radius `r1`), as a bone.
    void draw_capsule(point2 a, point2 b, double r0, double r1, color c, float alpha = 1.0f) noexcept
    {
        shape_capsule(a, b, r0, r1, c, alpha, true);
    }

    /// @brief A lit sphere (disc) of radius `r` at `p`, as a joint.
    void draw_ball(point2 p, double r, color c, float alpha = 1.0f) noexcept { shape_capsule(p, p, r, r, c, alpha, true); }

    /// @brief A flat disc of radius `r` at `p`.
    void fill_disc(point2 p, double r, color c, float alpha = 1.0f) noexcept { shape_capsule(p, p, r, r, c, alpha, false); }

    /// @brief Fills a convex polygon (vertices in either winding) with anti-aliased edges.
    /// Non-convex input is filled as its convex hull.
    void fill_convex(std::span<const point2> pts, color c, float alpha = 1.0f)
    {
        std::vector<point2> hull = convex_hull(pts);
        if (hull.size() < 3) return;
        double x0 = hull[0].x, x1 = x0, y0 = hull[0].y, y1 = y0;
        for (auto& p : hull) {
            x0 = std::min(x0, p.x), x1 = std::max(x1, p.x), y0 = std::min(y0, p.y), y1 = std::max(y1, p.y);
        }
        // Counter-clockwise hull in a y-down frame: the outward normal of edge (a -> b) is (dy, -dx).
        for (long y = clamp_y(y0 - 1); y < clamp_y(y1 + 2); ++y) {
            for (long x = clamp_x(x0 - 1); x < clamp_x(x1 + 2); ++x) {
                const double px = x + 0.5, py = y + 0.5;
                double d = -1e300;  // signed distance of a convex polygon ~ max over edges of the edge distance
                for (std::size_t i = 0; i < hull.size(); ++i) {
                    const point2 a = hull[i], b = hull[(i + 1) % hull.size()];
                    const double ex = b.x - a.x, ey = b.y - a.y, len = std::hypot(ex, ey);
                    if (len < 1e-12) continue;
                    d = std::max(d, ((px - a.x) * ey - (py - a.y) * ex) / len);
                }
                const double cov = std::clamp(0.5 - d, 0.0, 1.0);
                if (cov > 0) blend(x, y, c, alpha * static_cast<float>(cov));
            }
        }
    }

    /// @brief Copies `src` into this canvas with its top-left corner at (x, y) (clipped).
    void blit(const canvas& src, long x, long y) noexcept
    {
        for (std::size_t sy = 0; sy < src.height_; ++sy)
            for (std::size_t sx = 0; sx < src.width_; ++sx) blend(x + static_cast<long>(sx), y + static_cast<long>(sy), src.at(sx, sy), 1.0f);
    }

    /// @brief Row-major 8-bit RGB bytes, [height, width, 3], rounded and clamped.
    std::vector<std::uint8_t> to_rgb8() const
    {
        std::vector<std::uint8_t> out(data_.size());
        for (std::size_t i = 0; i < data_.size(); ++i)
            out[i] = static_cast<std::uint8_t>(std::lround(std::clamp(data_[i], 0.0f, 1.0f) * 255.0f));
        return out;
    }

    /// @brief The canvas as an 8-bit rgb_image (what write_png / write_bmp take).
    rgb_image to_image() const
    {
        rgb_image im;
        im.width = width_;
        im.height = height_;
        im.pixels = to_rgb8();
        return im;
    }

    /// @brief Convex hull (Andrew's monotone chain), counter-clockwise in a y-down frame as drawn.
    static std::vector<point2> convex_hull(std::span<const point2> pts)
    {
        std::vector<point2> p(pts.begin(), pts.end());
        std::sort(p.begin(), p.end(), [](point2 a, point2 b) { return a.x < b.x || (a.x == b.x && a.y < b.y); });
        if (p.size() < 3) return p;
        auto cross = [](point2 o, point2 a, point2 b) { return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x); };
        std::vector<point2> h(2 * p.size());
        std::size_t k = 0;
        for (std::size_t i = 0; i < p.size(); ++i) {
            while (k >= 2 && cross(h[k - 2], h[k - 1], p[i]) <= 0) --k;
            h[k++] = p[i];
        }
        for (std::size_t i = p.size() - 1, t = k + 1; i-- > 0;) {
            while (k >= t && cross(h[k - 2], h[k - 1], p[i]) <= 0) --k;
            h[k++] = p[i];
        }
        h.resize(k - 1);
        return h;
    }

private:
    long clamp_x(double v) const noexcept
    {
        return static_cast<long>(std::clamp(std::floor(v), 0.0, static_cast<double>(width_)));
    }
    long clamp_y(double v) const noexcept
    {
        return static_cast<long>(std::clamp(std::floor(v), 0.0, static_cast<double>(height_)));
    }

    /// Capsule coverage and shading. With t the projection parameter of the pixel centre on [a, b]
    /// (clamped to [0, 1]), c = a + t (b - a) and r(t) = r0 + t (r1 - r0), the signed distance is
    /// |p - c| - r(t). Lighting: L = normalise(-0.35, -0.5, 0.8) (upper left, toward the viewer),
    /// H = normalise(L + (0, 0, 1)); shade = base (0.35 + 0.65 max(n.L, 0)) + 0.35 max(n.H, 0)^24.
    void shape_capsule(point2 a, point2 b, double r0, double r1, color c, float alpha, bool lit) noexcept
    {
        if (!(r0 > 0) || !(r1 > 0) || !std::isfinite(a.x + a.y + b.x + b.y)) return;
        const double rmax = std::max(r0, r1);
        const double bx0 = std::min(a.x, b.x) - rmax - 1, bx1 = std::max(a.x, b.x) + rmax + 2;
        const double by0 = std::min(a.y, b.y) - rmax - 1, by1 = std::max(a.y, b.y) + rmax + 2;
        const double dx = b.x - a.x, dy = b.y - a.y, len2 = dx * dx + dy * dy;
        static constexpr double lx = -0.35 / 1.0025, ly = -0.5 / 1.0025, lz = 0.8 / 1.0025;  // |(-.35,-.5,.8)| ~ 1.0025
        const double hx = lx, hy = ly, hz = lz + 1.0, hn = std::sqrt(hx * hx + hy * hy + hz * hz);
        for (long y = clamp_y(by0); y < clamp_y(by1); ++y) {
            for (long x = clamp_x(bx0); x < clamp_x(bx1); ++x) {
                const double px = x + 0.5, py = y + 0.5;
                const double t = len2 > 0 ? std::clamp(((px - a.x) * dx + (py - a.y) * dy) / len2, 0.0, 1.0) : 0.0;
                const double cx = a.x + t * dx, cy = a.y + t * dy, r = r0 + t * (r1 - r0);
                const double ox = px - cx, oy = py - cy, dist = std::sqrt(ox * ox + oy * oy);
                const double cov = std::clamp(r - dist + 0.5, 0.0, 1.0);
                if (cov <= 0) continue;
                color out = c;
                if (lit) {
                    const double nx = std::clamp(ox / r, -1.0, 1.0), ny = std::clamp(oy / r, -1.0, 1.0);
                    const double nz = std::sqrt(std::max(0.0, 1.0 - nx * nx - ny * ny));
                    const double diff = std::max(0.0, nx * lx + ny * ly + nz * lz);
                    const double spec = std::pow(std::max(0.0, (nx * hx + ny * hy + nz * hz) / hn), 24.0);
                    const auto k = static_cast<float>(0.35 + 0.65 * diff), s = static_cast<float>(0.35 * spec);
                    out = {std::min(1.0f, c.r * k + s), std::min(1.0f, c.g * k + s), std::min(1.0f, c.b * k + s)};
                    // a thin darker rim separates overlapping bones of the same colour
                    if (dist > r - 1.0 && r > 2.5) out = scale(out, 0.7f);
                }
                blend(x, y, out, alpha * static_cast<float>(cov));
            }
        }
    }

    std::size_t width_ = 0, height_ = 0;
    std::vector<float> data_;
};

}  // namespace handemo
