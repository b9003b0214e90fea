// Map files: a rig whose joint names no built-in convention knows is described in JSON, slot -> joint name,
// in the slot names of conventions.hpp:
//     {"joints": {"hips": "pelvis_jnt", "l.thigh": "L_leg_up", ..., "r.hand": "R_wrist", "r.index1": "R_idx_a"}}
// Every entry is checked: an unknown slot, a joint the skeleton lacks, one joint named by two slots and a key
// written twice are errors naming the entry (make_map() also refuses a map that turns a chain around).
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/core/io.hpp>
#include <handemo/motion/skeleton.hpp>
#include <handemo/retarget/conventions.hpp>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>
#include <map>
#include <set>
#include <string>
#include <vector>

namespace handemo::retarget {

/// @brief Parses a map file's text against the skeleton it describes.
/// @param source names the file in messages.
/// @throws format_error for malformed JSON, a missing "joints" object, a key written twice or a value that is
/// not a string; value_error naming the entry for an unknown slot, a joint not in `s` or a joint named twice.
inline binding parse_map(std::string_view text, const skeleton& s, const std::string& source)
{
    const std::string where = "retarget: map " + source;
    nlohmann::json j;
    try {
        // keys written twice in one object: nlohmann would keep the last one silently
        std::vector<std::set<std::string>> keys;
        j = nlohmann::json::parse(text, [&](int depth, nlohmann::json::parse_event_t ev, nlohmann::json& v) {
            if (depth > 8) throw format_error(where + ": nests deeper than 8 levels");
            if (ev == nlohmann::json::parse_event_t::object_start) keys.emplace_back();
            else if (ev == nlohmann::json::parse_event_t::object_end && !keys.empty()) keys.pop_back();
            else if (ev == nlohmann::json::parse_event_t::key && !keys.empty() && !keys.back().insert(v.get<std::string>()).second)
                throw format_error(where + ": entry '" + v.get<std::string>() + "' is written twice");
            return true;
        });
    } catch (const nlohmann::json::exception& e) {
        throw format_error(where + ": not valid JSON: " + e.what());
    }
    if (!j.is_object() || !j.contains("joints") || !j.at("joints").is_object())
        throw format_error(where + ": expected an object with a \"joints\" object of slot -> joint name entries");
    const auto slots = all_slots();
    std::map<std::string, std::string> by_joint;  // joint -> slot, for duplicates
    binding b{source, {}};
    for (const auto& [slot, v] : j.at("joints").items()) {
        if (std::find(slots.begin(), slots.end(), slot) == slots.end())
            throw value_error(where + ": entry '" + slot + "': unknown slot (slots: hips, spine, chest, neck, head, l.upperarm, r.hand, r.index1 ... see the "
                                                      "retargeting docs)");
        if (!v.is_string()) throw format_error(where + ": entry '" + slot + "': the joint name must be a string, found " + v.dump());
        const std::string name = v.get<std::string>();
        std::size_t idx = s.size();
        for (std::size_t k = 0; k < s.size(); ++k)
            if (s.joints[k].name == name) idx = k;
        if (idx == s.size()) throw value_error(where + ": entry '" + slot + "': skeleton '" + s.name + "' has no joint '" + name + "'");
        if (const auto [it, fresh] = by_joint.emplace(name, slot); !fresh)
            throw value_error(where + ": entry '" + slot + "': joint '" + name + "' is already the joint of entry '" + it->second + "'");
        b.slots.emplace(slot, idx);
    }
    if (b.slots.empty()) throw value_error(where + ": \"joints\" is empty");
    return b;
}

/// @brief Reads a map file (parse_map()).
/// @throws io_error when it cannot be read, and what parse_map() throws.
inline binding read_map(const std::filesystem::path& path, const skeleton& s) { return parse_map(read_file(path), s, path.string()); }

/// @brief A binding written as a map file (what `handemo retarget --print-map` shows; a start for a custom map).
inline std::string map_to_json(const binding& b, const skeleton& s)
{
    nlohmann::ordered_json j;
    j["joints"] = nlohmann::ordered_json::object();
    for (const auto& key : all_slots())
        if (b.has(key)) j["joints"][key] = s.joints[b.at(key)].name;
    return j.dump(2) + "\n";
}

}  // namespace handemo::retarget
