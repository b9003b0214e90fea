// Header-only hygiene, first translation unit (this file is merged into its test group's unity unit;
// two_tu_b.cpp never is): includes the umbrella and image headers and uses inline functions that
// two_tu_b.cpp uses too; linking both into one program fails on any non-inline definition or a second
// stb implementation.
#include <handemo.hpp>
#include <handemo/image.hpp>

#include <string>

std::string two_tu_a_bvh(const handemo::clip& c) { return handemo::to_bvh_string(c); }

handemo::rgb_image two_tu_a_roundtrip(const std::filesystem::path& p, const handemo::rgb_image& im)
{
    handemo::write_png(p, im);
    return handemo::read_image(p);
}
