// Drawing a skeleton pose as a figure, for the filmstrips of the hand paper (Figures 4-12: screenshots of
// the hand motion, one frame per row). Works for any BVH skeleton: "hub" joints (three or more children,
// e.g. the palm, the hips, the chest) and the paths from the root to them form the grey trunk; every
// other joint belongs to the limb (finger, arm, leg, neck) that hangs off the trunk, and each limb gets its
// own colour (for the hand: thumb, index, middle, ring, pinky by name). A hand is viewed from the palm
// side with the fingers up; a body from a front three-quarter view with +Y up (BVH convention), facing
// taken from the feet. The pose is projected orthographically (screen x = p.right, y = p.up, depth =
// p.toward) and drawn back to front (painter's algorithm) with lit capsules and spheres.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/motion/clip.hpp>
#include <handemo/motion/skeleton.hpp>
#include <handemo/render/canvas.hpp>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstddef>
#include <numbers>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace handemo {

/// What a skeleton depicts; decides the view and colours.
enum class figure_kind { automatic, hand, body };

/// @brief How figures are drawn (shared by every frame of a filmstrip).
struct figure_options {
    figure_kind kind = figure_kind::automatic;  ///< automatic: hand when joints are named after fingers
    double yaw_deg = 30.0;       ///< body camera: turn about the up axis from the front view
    double pitch_deg = 12.0;     ///< body camera: elevation above the horizontal
    double hand_yaw_deg = 20.0;  ///< hand camera: turn about the finger axis from the palm view
    double hand_pitch_deg = 10.0;
    vec3 up{0, 1, 0};         ///< world up of body clips (BVH files are Y-up)
    int track = -1;           ///< follow the figure's horizontal centroid: -1 auto (bodies), 0 off, 1 on
    double bone_width = 0;    ///< bone radius as a fraction of the cell side; 0 = automatic
    color background{1, 1, 1};
    color trunk_color = color::rgb8(150, 150, 150);
};

/// @brief The per-joint drawing plan of one skeleton.
struct figure_layout {
    figure_kind kind = figure_kind::body;
    std::vector<int> limb_of;             ///< [J] limb index of each joint, -1 for the trunk
    std::vector<std::size_t> limb_heads;  ///< [limbs] first joint of each limb
    std::vector<color> limb_colors;       ///< [limbs]
    std::vector<unsigned char> hidden;    ///< [J] 1 for a ground anchor (a root above a 6-channel child)
    std::vector<std::size_t> children_count;  ///< [J]
    int palm = -1;                        ///< hub joint whose limbs span a palm polygon (hands), or -1
    color trunk_color = color::rgb8(150, 150, 150);

    /// Colour of the bone ending at joint `j` (its limb's colour, or the trunk's).
    color color_of(std::size_t j) const noexcept
    {
        return limb_of[j] < 0 ? trunk_color : limb_colors[static_cast<std::size_t>(limb_of[j])];
    }
};

namespace detail {

inline vec3 v_add(vec3 a, vec3 b) noexcept { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
inline vec3 v_sub(vec3 a, vec3 b) noexcept { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
inline vec3 v_mul(vec3 a, double s) noexcept { return {a[0] * s, a[1] * s, a[2] * s}; }
inline double v_dot(vec3 a, vec3 b) noexcept { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
inline vec3 v_cross(vec3 a, vec3 b) noexcept
{
    return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
inline double v_norm(vec3 a) noexcept { return std::sqrt(v_dot(a, a)); }
/// Unit vector along `a`, or `fallback` when `a` is (nearly) zero.
inline vec3 v_unit(vec3 a, vec3 fallback) noexcept
{
    const double n = v_norm(a);
    return n > 1e-12 ? v_mul(a, 1.0 / n) : fallback;
}
/// Component of `a` orthogonal to the unit vector `u`.
inline vec3 v_reject(vec3 a, vec3 u) noexcept { return v_sub(a, v_mul(u, v_dot(a, u))); }
/// Rodrigues: `v` rotated by `deg` about the unit axis `k`.
inline vec3 v_rotate(vec3 v, vec3 k, double deg) noexcept
{
    const double r = deg * std::numbers::pi / 180.0, c = std::cos(r), s = std::sin(r);
    return v_add(v_add(v_mul(v, c), v_mul(v_cross(k, v), s)), v_mul(k, v_dot(k, v) * (1 - c)));
}

inline std::string lower(std::string_view s)
{
    std::string r(s);
    for (auto& ch : r) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
    return r;
}

inline bool name_has(const skeleton& s, std::initializer_list<std::string_view> words)
{
    for (const auto& j : s.joints) {
        const std::string n = lower(j.name);
        for (auto w : words)
            if (n.find(w) != std::string::npos) return true;
    }
    return false;
}

/// Finger colour by joint name (thumb red, index orange, middle green, ring blue, pinky purple), or -1.
inline int finger_of_name(std::string_view name)
{
    const std::string n = lower(name);
    static constexpr std::array<std::array<std::string_view, 2>, 5> words{
        {{"thumb", "pollex"}, {"index", "point"}, {"middle", "mid"}, {"ring", "ring"}, {"pinky", "little"}}};
    for (std::size_t f = 0; f < words.size(); ++f)
        for (auto w : words[f])
            if (n.find(w) != std::string::npos) return static_cast<int>(f);
    return -1;
}

inline constexpr std::array<color, 5> finger_palette{color::rgb8(222, 62, 52), color::rgb8(240, 150, 30),
                                                     color::rgb8(60, 170, 75), color::rgb8(50, 110, 215),
                                                     color::rgb8(150, 75, 190)};
inline constexpr std::array<color, 8> limb_palette{
    color::rgb8(50, 110, 215), color::rgb8(222, 62, 52),  color::rgb8(60, 170, 75),  color::rgb8(240, 150, 30),
    color::rgb8(150, 75, 190), color::rgb8(30, 170, 180), color::rgb8(200, 80, 150), color::rgb8(130, 110, 60)};

}  // namespace detail

/// @brief Splits a skeleton into trunk and limbs and picks colours.
/// @param kind figure_kind::automatic decides hand when some joint is named after a finger (thumb, index,
///        pinky, ...) and none after a body part (hip, leg, spine, head, foot).
/// @throws format_error from skeleton::validate for a malformed hierarchy.
inline figure_layout analyse_figure(const skeleton& s, figure_kind kind = figure_kind::automatic,
                                    color trunk_color = color::rgb8(150, 150, 150))
{
    s.validate();
    const std::size_t n = s.size();
    figure_layout L;
    if (kind == figure_kind::automatic)
        kind = detail::name_has(s, {"thumb", "pinky", "index", "finger"}) &&
                       !detail::name_has(s, {"hip", "leg", "spine", "head", "foot", "neck"})
                   ? figure_kind::hand
                   : figure_kind::body;
    L.kind = kind;
    L.children_count.assign(n, 0);
    for (std::size_t i = 1; i < n; ++i)
        if (s.joints[i].parent >= 0) ++L.children_count[static_cast<std::size_t>(s.joints[i].parent)];

    // Hubs: joints with >= 3 children (>= 2 when there is none). Trunk: hubs and their ancestors.
    std::vector<unsigned char> trunk(n, 0);
    for (std::size_t min_children : {std::size_t{3}, std::size_t{2}}) {
        for (std::size_t i = 0; i < n; ++i) {
            if (L.children_count[i] < min_children) continue;
            for (int j = static_cast<int>(i); j >= 0 && !trunk[static_cast<std::size_t>(j)]; j = s.joints[static_cast<std::size_t>(j)].parent)
                trunk[static_cast<std::size_t>(j)] = 1;
        }
        if (std::find(trunk.begin(), trunk.end(), 1) != trunk.end()) break;
    }
    // a single chain: the root is the trunk, the rest one limb
    if (std::find(trunk.begin(), trunk.end(), 1) == trunk.end()) trunk[0] = 1;
    for (std::size_t i = 0; i < n; ++i)
        if (s.joints[i].parent < 0) trunk[i] = 1;

    L.limb_of.assign(n, -1);
    for (std::size_t i = 0; i < n; ++i) {
        if (trunk[i]) continue;
        const auto p = static_cast<std::size_t>(s.joints[i].parent);
        if (trunk[p]) {
            L.limb_of[i] = static_cast<int>(L.limb_heads.size());
            L.limb_heads.push_back(i);
        } else {
            L.limb_of[i] = L.limb_of[p];
        }
    }

    // Colours: hands by finger name where the names say, otherwise in limb order.
    std::size_t next = 0;
    for (std::size_t k = 0; k < L.limb_heads.size(); ++k) {
        if (kind == figure_kind::hand) {
            const int f = detail::finger_of_name(s.joints[L.limb_heads[k]].name);
            L.limb_colors.push_back(detail::finger_palette[static_cast<std::size_t>(f >= 0 ? f : static_cast<int>(k % 5))]);
        } else {
            L.limb_colors.push_back(detail::limb_palette[next++ % detail::limb_palette.size()]);
        }
    }

    // A root with a single child that has its own position channels is a ground anchor (Bandai's
    // joint_Root): its bone would run from the floor origin to the hips, so it is not drawn.
    L.hidden.assign(n, 0);
    for (std::size_t i = 0; i < n; ++i) {
        if (s.joints[i].parent >= 0 || L.children_count[i] != 1) continue;
        for (std::size_t c = i + 1; c < n; ++c)
            if (s.joints[c].parent == static_cast<int>(i) && s.joints[c].has_position()) L.hidden[i] = 1;
    }

    // The palm: for hands, the hub with the most limbs hanging off it.
    if (kind == figure_kind::hand) {
        std::size_t best = 0;
        for (std::size_t i = 0; i < n; ++i) {
            std::size_t limbs = 0;
            for (auto h : L.limb_heads)
                if (s.joints[h].parent == static_cast<int>(i)) ++limbs;
            if (limbs >= 3 && limbs > best) {
                best = limbs;
                L.palm = static_cast<int>(i);
            }
        }
    }
    L.trunk_color = trunk_color;
    return L;
}

/// @brief An orthographic camera: screen x = p.right, screen y (up) = p.up, depth toward the viewer =
/// p.toward; the three vectors are orthonormal and right-handed (right x up = toward).
struct view_basis {
    vec3 right{1, 0, 0}, up{0, 1, 0}, toward{0, 0, 1};
};

/// @brief One drawing primitive in world space: a bone (a != b) or a ball (a == b), or the palm polygon.
struct figure_primitive {
    enum class shape : unsigned char { bone, ball, palm } kind = shape::bone;
    vec3 a{}, b{};
    double radius = 1.0;  ///< relative to the figure's base bone radius
    color fill{};
    std::vector<vec3> polygon;  ///< palm outline points (shape::palm only)
};

namespace detail {

/// Camera from an up vector and a front direction: toward = front turned by `yaw` about up and raised by
/// `pitch`; right = up x toward (normalised); screen up = toward x right.
inline view_basis basis_from(vec3 up, vec3 front, double yaw_deg, double pitch_deg) noexcept
{
    up = v_unit(up, {0, 1, 0});
    vec3 helper = std::abs(up[2]) < 0.9 ? vec3{0, 0, 1} : vec3{1, 0, 0};
    front = v_unit(v_reject(front, up), v_unit(v_reject(helper, up), {1, 0, 0}));
    vec3 toward = v_rotate(front, up, yaw_deg);
    const double p = pitch_deg * std::numbers::pi / 180.0;
    toward = v_unit(v_add(v_mul(toward, std::cos(p)), v_mul(up, std::sin(p))), toward);
    view_basis v;
    v.toward = toward;
    v.right = v_unit(v_cross(up, toward), {1, 0, 0});
    v.up = v_cross(toward, v.right);
    return v;
}

/// Knuckles of a hand: for every limb hanging off the palm, its head's first child (or the head).
inline std::vector<std::size_t> knuckles(const skeleton& s, const figure_layout& L)
{
    std::vector<std::size_t> k;
    for (auto h : L.limb_heads) {
        if (s.joints[h].parent != L.palm) continue;
        std::size_t pick = h;
        for (std::size_t c = h + 1; c < s.size(); ++c)
            if (s.joints[c].parent == static_cast<int>(h)) {
                pick = c;
                break;
            }
        k.push_back(pick);
    }
    return k;
}

/// Palm frame of one pose: up = wrist -> mean knuckle, normal = (first-but-thumb knuckle - last) x up.
inline void palm_frame(const skeleton& s, const figure_layout& L, const pose_positions& P, vec3& up, vec3& normal)
{
    const auto ks = knuckles(s, L);
    const auto palm = static_cast<std::size_t>(L.palm);
    const std::size_t wrist = s.joints[palm].parent >= 0 ? static_cast<std::size_t>(s.joints[palm].parent) : palm;
    vec3 mean{};
    for (auto k : ks) mean = v_add(mean, P.joints[k]);
    mean = v_mul(mean, 1.0 / static_cast<double>(std::max<std::size_t>(ks.size(), 1)));
    up = v_unit(v_sub(mean, P.joints[wrist]), {0, 1, 0});
    const std::size_t first = ks.size() >= 3 ? ks[1] : ks.front();
    const vec3 lateral = v_reject(v_sub(P.joints[first], P.joints[ks.back()]), up);
    normal = v_unit(v_cross(lateral, up), v_unit(v_reject({0, 0, 1}, up), {1, 0, 0}));
}

/// Up to `max_frames` frame indices spread uniformly over a clip.
inline std::vector<std::size_t> sample_frames(std::size_t frames, std::size_t max_frames)
{
    std::vector<std::size_t> f;
    if (frames == 0) return f;
    const std::size_t n = std::min(frames, max_frames);
    for (std::size_t i = 0; i < n; ++i) f.push_back(n == 1 ? 0 : i * (frames - 1) / (n - 1));
    return f;
}

}  // namespace detail

/// @brief Forward kinematics of frame `f` of a clip (angles and position channels).
inline pose_positions clip_pose(const clip& c, std::size_t f)
{
    return forward_kinematics(c.skel, c.frame_angles(f), c.frame_positions(f));
}

/// @brief Chooses the camera for a set of clips drawn together (from the first clip).
/// Hand: looks at the palm (the side the finger tips curl toward over all frames), fingers up, turned by
/// hand_yaw_deg. Body: `up` from the options, front from the direction the feet point (toes minus ankles
/// of the lowest leaves in the first frame; +Z when there are none), turned by yaw_deg, raised by pitch_deg.
inline view_basis choose_view(std::span<const clip> clips, const figure_layout& L, const figure_options& o)
{
    if (clips.empty() || clips.front().frames == 0) return {};
    const clip& c0 = clips.front();
    const skeleton& s = c0.skel;
    const pose_positions P0 = clip_pose(c0, 0);
    if (L.kind == figure_kind::hand && L.palm >= 0 && !detail::knuckles(s, L).empty()) {
        vec3 up, normal;
        detail::palm_frame(s, L, P0, up, normal);
        // sign: finger tips move to the palm side when they flex (x = flexion toward the palm)
        double side = 0;
        for (const clip& c : clips) {
            if (!c.skel.same_topology(s)) continue;
            for (auto f : detail::sample_frames(c.frames, 64)) {
                const pose_positions P = clip_pose(c, f);
                vec3 uf, nf;
                detail::palm_frame(s, L, P, uf, nf);
                for (std::size_t j = 0; j < s.size(); ++j)
                    if (L.limb_of[j] >= 0 && L.children_count[j] == 0)
                        side += detail::v_dot(detail::v_sub(P.end_sites[j], P.joints[static_cast<std::size_t>(L.palm)]), nf);
            }
        }
        if (side < 0) normal = detail::v_mul(normal, -1.0);
        return detail::basis_from(up, normal, o.hand_yaw_deg, o.hand_pitch_deg);
    }
    // Body: facing from the feet, averaged over the first clip's frames (a single frame can be mid-stride
    // with the foot pitched): the horizontal part of (toe end - toe joint), or (toe joint - ankle) where the
    // end site has zero length, summed unnormalised over the lowest leaves of each sampled pose.
    const vec3 up = detail::v_unit(o.up, {0, 1, 0});
    vec3 front{};
    for (auto f : detail::sample_frames(c0.frames, 64)) {
        const pose_positions P = clip_pose(c0, f);
        double hmin = 1e300, hmax = -1e300;
        for (std::size_t j = 0; j < s.size(); ++j) {
            if (L.hidden[j]) continue;
            hmin = std::min(hmin, detail::v_dot(P.end_sites[j], up));
            hmax = std::max(hmax, detail::v_dot(P.end_sites[j], up));
        }
        for (std::size_t j = 0; j < s.size(); ++j) {
            if (L.hidden[j] || L.children_count[j] != 0 || s.joints[j].parent < 0) continue;
            if (detail::v_dot(P.end_sites[j], up) > hmin + 0.2 * (hmax - hmin)) continue;
            const auto p = static_cast<std::size_t>(s.joints[j].parent);
            vec3 d = detail::v_sub(P.end_sites[j], P.joints[j]);
            if (detail::v_norm(d) < 1e-9) d = detail::v_sub(P.joints[j], P.joints[p]);
            front = detail::v_add(front, detail::v_reject(d, up));
        }
    }
    if (detail::v_norm(front) < 1e-6) front = {0, 0, 1};
    return detail::basis_from(up, front, o.yaw_deg, o.pitch_deg);
}

/// @brief The world-space primitives of one pose (bones, joint balls, palm), before projection.
/// @param track subtracted from every point (the figure's horizontal centroid when tracking).
inline std::vector<figure_primitive> figure_primitives(const skeleton& s, const figure_layout& L,
                                                       const pose_positions& P, vec3 track = {})
{
    using detail::v_sub;
    std::vector<figure_primitive> out;
    const std::size_t n = s.size();
    const bool hand = L.kind == figure_kind::hand;
    auto at = [&](vec3 p) { return v_sub(p, track); };
    auto limb_depth = [&](std::size_t j) {
        int d = 0;
        for (int k = static_cast<int>(j); k >= 0 && L.limb_of[static_cast<std::size_t>(k)] >= 0 &&
                                           !(std::find(L.limb_heads.begin(), L.limb_heads.end(), static_cast<std::size_t>(k)) != L.limb_heads.end());
             k = s.joints[static_cast<std::size_t>(k)].parent)
            ++d;
        return d;
    };
    if (hand && L.palm >= 0) {
        figure_primitive poly;
        poly.kind = figure_primitive::shape::palm;
        const auto palm = static_cast<std::size_t>(L.palm);
        poly.polygon.push_back(at(P.joints[palm]));
        if (s.joints[palm].parent >= 0) poly.polygon.push_back(at(P.joints[static_cast<std::size_t>(s.joints[palm].parent)]));
        for (auto h : L.limb_heads)
            if (s.joints[h].parent == L.palm) poly.polygon.push_back(at(P.joints[h]));
        for (auto k : detail::knuckles(s, L)) poly.polygon.push_back(at(P.joints[k]));
        poly.fill = color::rgb8(238, 212, 190);
        out.push_back(std::move(poly));
    }
    for (std::size_t j = 0; j < n; ++j) {
        if (L.hidden[j]) continue;
        const int p = s.joints[j].parent;
        const color c = L.color_of(j);
        const double r = L.limb_of[j] < 0 ? 1.25 : std::max(0.55, 1.0 - 0.12 * limb_depth(j));
        if (p >= 0 && !L.hidden[static_cast<std::size_t>(p)]) {
            vec3 a = P.joints[static_cast<std::size_t>(p)];
            // hands: the forearm (bone from the root) is drawn as a stub of 30% of its length at the wrist
            if (hand && s.joints[static_cast<std::size_t>(p)].parent < 0)
                a = detail::v_add(P.joints[j], detail::v_mul(v_sub(a, P.joints[j]), 0.3));
            if (detail::v_norm(v_sub(a, P.joints[j])) > 1e-9)
                out.push_back({figure_primitive::shape::bone, at(a), at(P.joints[j]), r, c, {}});
        }
        if (detail::v_norm(v_sub(P.end_sites[j], P.joints[j])) > 1e-9) {
            out.push_back({figure_primitive::shape::bone, at(P.joints[j]), at(P.end_sites[j]), r * 0.85, c, {}});
            out.push_back({figure_primitive::shape::ball, at(P.end_sites[j]), at(P.end_sites[j]), r * 0.85, c, {}});
        }
        if (hand && s.joints[j].parent < 0) continue;  // no ball at the cut end of the forearm
        out.push_back({figure_primitive::shape::ball, at(P.joints[j]), at(P.joints[j]), r * 1.1, c, {}});
    }
    return out;
}

/// @brief Screen placement of figures: view-space point (x, y) maps to (origin.x + (x - cx) scale,
/// origin.y - (y - cy) scale); depth in [depth_min, depth_max] fades far primitives toward the background.
struct figure_projection {
    view_basis view;
    double cx = 0, cy = 0, scale = 1;
    double depth_min = 0, depth_max = 1;
    double radius_px = 3;  ///< base bone radius in pixels
};

/// @brief Draws one pose's primitives into `cv` with its view-space centre at pixel `origin`.
/// Painter's algorithm: primitives sorted far to near by the mean depth of their end points (balls get a
/// small bias toward the viewer so a joint covers the ends of its bones; the palm a small bias away).
inline void draw_figure(canvas& cv, std::span<const figure_primitive> prims, const figure_projection& pr,
                        point2 origin, color background)
{
    using detail::v_dot;
    const view_basis& v = pr.view;
    auto project = [&](vec3 p) {
        return point2{origin.x + (v_dot(p, v.right) - pr.cx) * pr.scale, origin.y - (v_dot(p, v.up) - pr.cy) * pr.scale};
    };
    const double span = std::max(pr.depth_max - pr.depth_min, 1e-9);
    struct item {
        double depth;
        std::size_t index;
    };
    std::vector<item> order;
    order.reserve(prims.size());
    for (std::size_t i = 0; i < prims.size(); ++i) {
        const auto& q = prims[i];
        double d = 0.5 * (v_dot(q.a, v.toward) + v_dot(q.b, v.toward));
        if (q.kind == figure_primitive::shape::ball) d += 0.004 * span;
        if (q.kind == figure_primitive::shape::palm) {
            d = 0;
            for (auto& p : q.polygon) d += v_dot(p, v.toward);
            d = d / static_cast<double>(std::max<std::size_t>(q.polygon.size(), 1)) - 0.02 * span;
        }
        order.push_back({d, i});
    }
    std::stable_sort(order.begin(), order.end(), [](const item& x, const item& y) { return x.depth < y.depth; });
    for (const auto& it : order) {
        const auto& q = prims[it.index];
        const float fade = static_cast<float>(0.35 * std::clamp((pr.depth_max - it.depth) / span, 0.0, 1.0));
        const color c = mix(q.fill, background, fade);
        const double r = q.radius * pr.radius_px;
        switch (q.kind) {
        case figure_primitive::shape::bone: cv.draw_capsule(project(q.a), project(q.b), r, r * 0.92, c); break;
        case figure_primitive::shape::ball: cv.draw_ball(project(q.a), r, mix(c, color{0.2f, 0.2f, 0.2f}, 0.15f)); break;
        case figure_primitive::shape::palm: {
            std::vector<point2> pts;
            for (auto& p : q.polygon) pts.push_back(project(p));
            cv.fill_convex(pts, c);
            const auto hull = canvas::convex_hull(pts);
            for (std::size_t i = 0; i < hull.size(); ++i)
                cv.draw_line(hull[i], hull[(i + 1) % hull.size()], 1.5, scale(c, 0.8f));
            break;
        }
        }
    }
}

}  // namespace handemo
