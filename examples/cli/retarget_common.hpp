// What `handemo transfer` and `handemo retarget` share: reading --hand and telling the user how a capture was
// mapped (the convention found, the hand, what is driven and what is carried through untouched).
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/retarget.hpp>

#include <iostream>
#include <string>

namespace handemo::cli {

/// --hand left|right -> 'l' / 'r'; empty -> 0.
inline char hand_side(const std::string& h)
{
    if (h.empty()) return 0;
    if (h == "left") return 'l';
    if (h == "right") return 'r';
    throw value_error("--hand " + h + ": expected left or right");
}

inline void print_map_summary(const std::string& cmd, const std::string& file, const retarget::retarget_map& m)
{
    std::cout << cmd << ": " << file << ": " << m.source.size() << " joints, convention " << m.source_slots.convention << " -> "
              << m.target.name << " (" << m.target_slots.convention << "): ";
    if (m.kind == retarget::target_kind::hand)
        std::cout << (m.source_side == 'l' ? "left" : "right") << " hand" << (m.mirror ? " (mirrored)" : "") << ", relative to '"
                  << m.source.joints[m.source_anchor].name << "'";
    else
        std::cout << "body, scale " << m.scale;
    std::cout << "; " << m.pairs.size() << " joints driven, " << m.unmapped_source().size() << " carried through unchanged\n";
}

}  // namespace handemo::cli
