// Joint roles for the circumplex (RCM) analysis of Aristidou et al. 2017 (Section 3.1): the LMA features of
// Table 1 speak of "head", "chest", "pelvis", "left hand", ... and this file finds those joints in any
// skeleton from their names (Bandai `Hand_L`, Xia/CMU `LeftHand`, Mixamo `mixamorig:LeftHand`, the 23-joint
// hand's `index_distal_end`), with a JSON override file `{"roles": {"left_hand": "Hand_L", ...}}` for names
// the rules do not know. Features are computed on *points*: the skeleton's joints followed by the End Sites
// of the joints that have one (named `<joint>_end`), so the hand's fingertips are points too.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/core/io.hpp>
#include <handemo/motion/clip.hpp>
#include <handemo/motion/skeleton.hpp>

#include <nlohmann/json.hpp>

#include <array>
#include <cctype>
#include <cstddef>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace handemo::rcm {

/// @brief A body or hand landmark the features of lma.hpp refer to.
enum class role : std::uint8_t {
    // body
    head, neck, chest, pelvis,
    left_shoulder, right_shoulder, left_elbow, right_elbow, left_hand, right_hand,
    left_hip, right_hip, left_knee, right_knee, left_foot, right_foot,
    // hand (the 23-joint hand of hand.hpp or any hand with five named fingers)
    wrist, palm,
    thumb_base, index_base, middle_base, ring_base, pinky_base,
    thumb_tip, index_tip, middle_tip, ring_tip, pinky_tip,
};
inline constexpr std::size_t role_count = 28;
inline constexpr std::size_t body_role_count = 16;  ///< roles head .. right_foot
inline constexpr std::size_t hand_role_first = 16;  ///< wrist is the first hand role

/// @brief The name of a role as used in the override file: `left_hand`, `index_tip`, ...
constexpr std::string_view to_string(role r) noexcept
{
    constexpr std::string_view n[] = {"head", "neck", "chest", "pelvis", "left_shoulder", "right_shoulder", "left_elbow",
                                      "right_elbow", "left_hand", "right_hand", "left_hip", "right_hip", "left_knee",
                                      "right_knee", "left_foot", "right_foot", "wrist", "palm", "thumb_base", "index_base",
                                      "middle_base", "ring_base", "pinky_base", "thumb_tip", "index_tip", "middle_tip",
                                      "ring_tip", "pinky_tip"};
    return n[static_cast<int>(r)];
}

/// @brief Parses a role name.
/// @throws value_error naming the unknown name.
inline role role_from_string(std::string_view s)
{
    for (std::size_t i = 0; i < role_count; ++i)
        if (to_string(static_cast<role>(i)) == s) return static_cast<role>(i);
    throw value_error("rcm roles: unknown role '" + std::string(s) + "'");
}

/// @brief Which feature set a skeleton gets: the 37 body features of Table 1, or the hand variant.
enum class feature_set : std::uint8_t { body, hand };
constexpr std::string_view to_string(feature_set f) noexcept { return f == feature_set::body ? "body" : "hand"; }
inline feature_set feature_set_from_string(std::string_view s)
{
    if (s == "body") return feature_set::body;
    if (s == "hand") return feature_set::hand;
    throw value_error("rcm: feature set '" + std::string(s) + "' is not 'body' or 'hand'");
}

/// @brief Names of the points of a skeleton: its joints, then `<joint>_end` for each joint with an End Site.
inline std::vector<std::string> point_names(const skeleton& s)
{
    std::vector<std::string> n;
    n.reserve(s.size() * 2);
    for (const auto& j : s.joints) n.push_back(j.name);
    for (const auto& j : s.joints)
        if (j.end_site) n.push_back(j.name + "_end");
    return n;
}

/// @brief Role -> point index for one skeleton; -1 where a role was not found.
struct role_map {
    std::array<int, role_count> index{};
    std::vector<std::string> points;  ///< point names of the skeleton (point_names())

    role_map() { index.fill(-1); }
    bool has(role r) const noexcept { return index[static_cast<std::size_t>(r)] >= 0; }
    /// @brief Point index of a role.
    /// @throws value_error naming the missing role and the skeleton's points when it was not found.
    std::size_t at(role r) const
    {
        const int i = index[static_cast<std::size_t>(r)];
        if (i < 0) {
            std::string list;
            for (std::size_t k = 0; k < points.size() && k < 40; ++k) list += (k ? ", " : "") + points[k];
            throw value_error("rcm roles: no joint found for role '" + std::string(to_string(r)) +
                              "' (give it in a roles file: {\"roles\": {\"" + std::string(to_string(r)) +
                              "\": \"<joint name>\"}}); joints: " + list);
        }
        return static_cast<std::size_t>(i);
    }
    /// @brief Checks that every role a feature set needs is present.
    /// @throws value_error naming the first missing role.
    void require(feature_set f) const
    {
        const std::size_t lo = f == feature_set::body ? 0 : hand_role_first;
        const std::size_t hi = f == feature_set::body ? body_role_count : role_count;
        for (std::size_t r = lo; r < hi; ++r) (void)at(static_cast<role>(r));
    }
    /// @brief The role map as JSON `{"head": "Head", ...}` (found roles only).
    nlohmann::json to_json() const
    {
        nlohmann::json j = nlohmann::json::object();
        for (std::size_t r = 0; r < role_count; ++r)
            if (index[r] >= 0) j[std::string(to_string(static_cast<role>(r)))] = points[static_cast<std::size_t>(index[r])];
        return j;
    }
};

namespace detail {

enum class side : std::uint8_t { none, left, right };

/// Splits a joint name into lower-case tokens at non-alphanumerics and lower->upper case changes, after
/// dropping a `namespace:` prefix (Mixamo).
inline std::vector<std::string> name_tokens(std::string_view name)
{
    const auto colon = name.rfind(':');
    if (colon != std::string_view::npos) name = name.substr(colon + 1);
    std::vector<std::string> out;
    std::string cur;
    for (std::size_t i = 0; i < name.size(); ++i) {
        const unsigned char c = static_cast<unsigned char>(name[i]);
        if (!std::isalnum(c)) {
            if (!cur.empty()) out.push_back(cur), cur.clear();
            continue;
        }
        if (std::isupper(c) && !cur.empty() && i > 0 && (std::islower(static_cast<unsigned char>(name[i - 1])) ||
                                                         std::isdigit(static_cast<unsigned char>(name[i - 1])))) {
            out.push_back(cur);
            cur.clear();
        } else if (std::isupper(c) && !cur.empty() && i + 1 < name.size() && std::islower(static_cast<unsigned char>(name[i + 1])) &&
                   std::isupper(static_cast<unsigned char>(name[i - 1]))) {
            // "LHip": L | Hip
            out.push_back(cur);
            cur.clear();
        }
        cur += static_cast<char>(std::tolower(c));
    }
    if (!cur.empty()) out.push_back(cur);
    return out;
}

/// Side of a name and its base (the other tokens joined): `UpperArm_L` -> (left, "upperarm").
inline std::pair<side, std::string> side_and_base(std::string_view name)
{
    side s = side::none;
    std::string base;
    for (const auto& t : name_tokens(name)) {
        if (s == side::none && (t == "l" || t == "left")) {
            s = side::left;
            continue;
        }
        if (s == side::none && (t == "r" || t == "right")) {
            s = side::right;
            continue;
        }
        base += t;
    }
    return {s, base};
}

struct role_rule {
    role r;
    side s;
    std::vector<std::string_view> bases;  ///< accepted base names, best first
};

inline const std::vector<role_rule>& role_rules()
{
    static const std::vector<role_rule> rules = [] {
        std::vector<role_rule> v;
        v.push_back({role::head, side::none, {"head"}});
        v.push_back({role::neck, side::none, {"neck", "neck1"}});
        v.push_back({role::chest, side::none, {"chest", "upperchest", "spine3", "spine2", "spine1", "thorax", "spine"}});
        v.push_back({role::pelvis, side::none, {"hips", "pelvis", "hip", "root", "jointroot"}});
        for (side s : {side::left, side::right}) {
            const bool l = s == side::left;
            v.push_back({l ? role::left_shoulder : role::right_shoulder, s, {"upperarm", "arm", "humerus", "shoulder"}});
            v.push_back({l ? role::left_elbow : role::right_elbow, s, {"lowerarm", "forearm", "elbow"}});
            v.push_back({l ? role::left_hand : role::right_hand, s, {"hand", "wrist"}});
            v.push_back({l ? role::left_hip : role::right_hip, s, {"upperleg", "upleg", "thigh", "femur", "hip", "hipjoint"}});
            v.push_back({l ? role::left_knee : role::right_knee, s, {"lowerleg", "leg", "knee", "shin", "calf", "tibia"}});
            v.push_back({l ? role::left_foot : role::right_foot, s, {"foot", "ankle"}});
        }
        v.push_back({role::wrist, side::none, {"wrist", "hand"}});
        v.push_back({role::palm, side::none, {"palm"}});
        constexpr std::string_view fingers[] = {"thumb", "index", "middle", "ring", "pinky"};
        static const std::array<std::array<std::string, 4>, 5> base_names = [] {
            std::array<std::array<std::string, 4>, 5> b;
            const char* f[] = {"thumb", "index", "middle", "ring", "pinky"};
            for (int i = 0; i < 5; ++i) b[i] = {std::string(f[i]) + "proximal", std::string(f[i]) + "1", std::string(f[i]) + "mcp", ""};
            return b;
        }();
        static const std::array<std::array<std::string, 4>, 5> tip_names = [] {
            std::array<std::array<std::string, 4>, 5> b;
            const char* f[] = {"thumb", "index", "middle", "ring", "pinky"};
            for (int i = 0; i < 5; ++i)
                b[i] = {std::string(f[i]) + "distalend", std::string(f[i]) + "tip", std::string(f[i]) + "end", std::string(f[i]) + "4"};
            return b;
        }();
        for (int f = 0; f < 5; ++f) {
            (void)fingers;
            role_rule base{static_cast<role>(static_cast<int>(role::thumb_base) + f), side::none, {}};
            for (const auto& n : base_names[static_cast<std::size_t>(f)])
                if (!n.empty()) base.bases.push_back(n);
            v.push_back(base);
            role_rule tip{static_cast<role>(static_cast<int>(role::thumb_tip) + f), side::none, {}};
            for (const auto& n : tip_names[static_cast<std::size_t>(f)]) tip.bases.push_back(n);
            v.push_back(tip);
        }
        return v;
    }();
    return rules;
}

}  // namespace detail

/// @brief Finds the roles of a skeleton's points from their names (first matching point in skeleton
/// order for the best-ranked accepted name; roles with no match stay -1).
inline role_map find_roles(const std::vector<std::string>& points)
{
    role_map m;
    m.points = points;
    std::vector<std::pair<detail::side, std::string>> parsed;
    parsed.reserve(points.size());
    for (const auto& p : points) parsed.push_back(detail::side_and_base(p));
    for (const auto& rule : detail::role_rules()) {
        for (std::string_view b : rule.bases) {
            int found = -1;
            for (std::size_t i = 0; i < points.size() && found < 0; ++i)
                if (parsed[i].first == rule.s && parsed[i].second == b) found = static_cast<int>(i);
            if (found >= 0) {
                m.index[static_cast<std::size_t>(rule.r)] = found;
                break;
            }
        }
    }
    return m;
}

/// @brief find_roles() on a skeleton's points (point_names()).
inline role_map find_roles(const skeleton& s) { return find_roles(point_names(s)); }

/// @brief Applies an override object `{"left_hand": "Hand_L", ...}` (role name -> point name).
/// @throws format_error naming `what` and the role or point that is unknown.
inline void apply_role_overrides(role_map& m, const nlohmann::json& roles, const std::string& what)
{
    if (!roles.is_object()) throw format_error(what + ": field 'roles' is not an object");
    for (const auto& [key, val] : roles.items()) {
        role r{};
        try {
            r = role_from_string(key);
        } catch (const value_error& e) {
            throw format_error(what + ": roles." + key + ": " + e.what());
        }
        if (!val.is_string()) throw format_error(what + ": roles." + key + " is not a string");
        const std::string name = val.get<std::string>();
        int found = -1;
        for (std::size_t i = 0; i < m.points.size(); ++i)
            if (m.points[i] == name) found = static_cast<int>(i);
        if (found < 0) throw format_error(what + ": roles." + key + ": no joint named '" + name + "' in the skeleton");
        m.index[static_cast<std::size_t>(r)] = found;
    }
}

/// @brief find_roles() then the overrides of a JSON file `{"roles": {...}}`.
/// @throws io_error / format_error naming the file and field.
inline role_map find_roles(const skeleton& s, const std::filesystem::path& override_file)
{
    role_map m = find_roles(s);
    nlohmann::json j;
    try {
        j = nlohmann::json::parse(read_file(override_file));
    } catch (const nlohmann::json::parse_error& e) {
        throw format_error("rcm roles: " + override_file.string() + ": not JSON: " + e.what());
    }
    if (!j.is_object() || !j.contains("roles")) throw format_error("rcm roles: " + override_file.string() + ": no field 'roles'");
    apply_role_overrides(m, j["roles"], "rcm roles: " + override_file.string());
    return m;
}

/// @brief The feature set a skeleton gets: hand when it has the hand roles (wrist, palm, five tips) and no
/// left/right hands, else body.
inline feature_set detect_feature_set(const role_map& m)
{
    bool hand = true;
    for (std::size_t r = hand_role_first; r < role_count; ++r) hand = hand && m.has(static_cast<role>(r));
    return hand && !m.has(role::left_hand) ? feature_set::hand : feature_set::body;
}

}  // namespace handemo::rcm
