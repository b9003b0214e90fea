// Tests of BMP/PNG image I/O: lossless round trips (odd widths that need BMP row padding), and every
// refusal: missing, truncated, corrupt, wrong format, grayscale/RGBA/16-bit, wrong size, absurd size.
// The bad files are made inside the test.
#include <doctest/doctest.h>
#include <handemo/image.hpp>

#include <cstdint>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include <unistd.h>

namespace fs = std::filesystem;
using namespace handemo;

namespace {

struct temp_dir {
    fs::path path = fs::temp_directory_path() / ("handemo_image_test_" + std::to_string(::getpid()));
    temp_dir() { fs::create_directories(path); }
    ~temp_dir() { fs::remove_all(path); }
    fs::path operator/(const std::string& name) const { return path / name; }
};

rgb_image random_image(std::size_t w, std::size_t h, unsigned seed)
{
    rgb_image im = rgb_image::make(w, h);
    std::mt19937 rng(seed);
    for (auto& p : im.pixels) p = static_cast<std::uint8_t>(rng() & 0xFF);
    return im;
}

void append_be32(std::string& s, std::uint32_t v)
{
    for (int k = 3; k >= 0; --k) s += static_cast<char>((v >> (8 * k)) & 0xFF);
}

std::uint32_t crc32(const std::string& s)
{
    std::uint32_t c = 0xFFFFFFFFu;
    for (unsigned char b : s) {
        c ^= b;
        for (int k = 0; k < 8; ++k) c = (c >> 1) ^ (0xEDB88320u & (0u - (c & 1u)));
    }
    return c ^ 0xFFFFFFFFu;
}

void append_chunk(std::string& png, const std::string& type, const std::string& data)
{
    append_be32(png, static_cast<std::uint32_t>(data.size()));
    png += type + data;
    append_be32(png, crc32(type + data));
}

/// A valid w x h 16-bit RGB PNG (zlib "stored" block, no compression).
std::string png16(std::uint32_t w, std::uint32_t h)
{
    std::string raw;
    for (std::uint32_t r = 0; r < h; ++r) {
        raw += '\0';
        for (std::uint32_t i = 0; i < w * 6; ++i) raw += static_cast<char>(i * 37 + r);
    }
    std::string z = "\x78\x01";
    z += '\x01';  // final stored block
    const auto n = static_cast<std::uint16_t>(raw.size());
    z += static_cast<char>(n & 0xFF), z += static_cast<char>(n >> 8);
    z += static_cast<char>(~n & 0xFF), z += static_cast<char>((~n >> 8) & 0xFF);
    z += raw;
    std::uint32_t a = 1, b = 0;
    for (unsigned char ch : raw) a = (a + ch) % 65521, b = (b + a) % 65521;
    append_be32(z, (b << 16) | a);
    std::string ihdr;
    append_be32(ihdr, w), append_be32(ihdr, h);
    ihdr += std::string("\x10\x02\x00\x00\x00", 5);  // depth 16, color type 2 (RGB)
    std::string png("\x89PNG\r\n\x1a\n", 8);
    append_chunk(png, "IHDR", ihdr);
    append_chunk(png, "IDAT", z);
    append_chunk(png, "IEND", "");
    return png;
}

void put_le32(std::string& s, std::size_t at, std::uint32_t v)
{
    for (std::size_t k = 0; k < 4; ++k) s[at + k] = static_cast<char>((v >> (8 * k)) & 0xFF);
}

}  // namespace

TEST_CASE("image: BMP and PNG round trips are lossless")
{
    temp_dir dir;
    for (auto [w, h] : {std::pair<std::size_t, std::size_t>{23, 9}, {1, 1}, {5, 3}, {64, 48}}) {
        CAPTURE(w);
        CAPTURE(h);
        const rgb_image im = random_image(w, h, static_cast<unsigned>(w * 131 + h));
        write_bmp(dir / "a.bmp", im);
        write_png(dir / "a.png", im);
        CHECK(read_image(dir / "a.bmp") == im);
        CHECK(read_image(dir / "a.png") == im);
        CHECK(read_image(dir / "a.png", w, h) == im);
    }
    // at(row, col) addresses row-major RGB; BMP is stored bottom-up, so row order is a real check.
    rgb_image im = rgb_image::make(3, 2);
    im.at(0, 2)[0] = 200;
    im.at(1, 0)[2] = 7;
    CHECK(im.pixels[2 * 3 + 0] == 200);
    CHECK(im.pixels[(1 * 3 + 0) * 3 + 2] == 7);
    write_bmp(dir / "b.bmp", im);
    const rgb_image back = read_image(dir / "b.bmp");
    CHECK(back.at(0, 2)[0] == 200);
    CHECK(back.at(1, 0)[2] == 7);
    // 24-bit BMP size: 54-byte header + rows padded to 4 bytes.
    CHECK(fs::file_size(dir / "b.bmp") == 54 + 12 * 2);
}

TEST_CASE("image: missing, truncated, corrupt and foreign files are refused")
{
    temp_dir dir;
    CHECK_THROWS_WITH_AS((void)read_image(dir / "none.png"), doctest::Contains("none.png"), io_error);

    const rgb_image im = random_image(23, 9, 1);
    write_bmp(dir / "a.bmp", im);
    write_png(dir / "a.png", im);
    const std::string bmp = read_file(dir / "a.bmp"), png = read_file(dir / "a.png");

    write_file_atomic(dir / "cut.bmp", bmp.substr(0, bmp.size() / 2));
    CHECK_THROWS_WITH_AS((void)read_image(dir / "cut.bmp"), doctest::Contains("truncated BMP"), format_error);
    write_file_atomic(dir / "cut2.bmp", bmp.substr(0, 20));
    CHECK_THROWS_WITH_AS((void)read_image(dir / "cut2.bmp"), doctest::Contains("cut2.bmp"), format_error);
    write_file_atomic(dir / "cut.png", png.substr(0, png.size() - 30));
    CHECK_THROWS_WITH_AS((void)read_image(dir / "cut.png"), doctest::Contains("corrupt or truncated PNG"), format_error);
    std::string garbage = png;
    for (std::size_t i = 40; i < garbage.size(); ++i) garbage[i] = static_cast<char>(i * 7);
    write_file_atomic(dir / "garbage.png", garbage);
    CHECK_THROWS_WITH_AS((void)read_image(dir / "garbage.png"), doctest::Contains("garbage.png"), format_error);
    write_file_atomic(dir / "text.png", "hello, not an image");
    CHECK_THROWS_WITH_AS((void)read_image(dir / "text.png"), doctest::Contains("not a BMP or PNG"), format_error);
    write_file_atomic(dir / "empty.bmp", "");
    CHECK_THROWS_AS((void)read_image(dir / "empty.bmp"), format_error);
}

TEST_CASE("image: grayscale, RGBA and 16-bit images are refused with the channel count or depth")
{
    temp_dir dir;
    const std::vector<std::uint8_t> px(4 * 3 * 4, 100);
    REQUIRE(stbi_write_png((dir / "gray.png").string().c_str(), 4, 3, 1, px.data(), 4));
    CHECK_THROWS_WITH_AS((void)read_image(dir / "gray.png"), doctest::Contains("1 channel found, expected 3"), format_error);
    REQUIRE(stbi_write_png((dir / "ga.png").string().c_str(), 4, 3, 2, px.data(), 8));
    CHECK_THROWS_WITH_AS((void)read_image(dir / "ga.png"), doctest::Contains("2 channels found, expected 3"), format_error);
    REQUIRE(stbi_write_png((dir / "rgba.png").string().c_str(), 4, 3, 4, px.data(), 16));
    CHECK_THROWS_WITH_AS((void)read_image(dir / "rgba.png"), doctest::Contains("4 channels found, expected 3"), format_error);
    REQUIRE(stbi_write_bmp((dir / "rgba.bmp").string().c_str(), 4, 3, 4, px.data()));
    CHECK_THROWS_WITH_AS((void)read_image(dir / "rgba.bmp"), doctest::Contains("4 channels found"), format_error);

    const std::string p16 = png16(3, 2);
    write_file_atomic(dir / "deep.png", p16);
    int w = 0, h = 0, n = 0;
    stbi_us* ok = stbi_load_16_from_memory(reinterpret_cast<const stbi_uc*>(p16.data()), static_cast<int>(p16.size()), &w, &h, &n, 0);
    REQUIRE_MESSAGE(ok != nullptr, "the hand-made 16-bit PNG is itself valid");
    stbi_image_free(ok);
    CHECK_THROWS_WITH_AS((void)read_image(dir / "deep.png"), doctest::Contains("3 channels of 16 bits found, expected 3 (8-bit RGB)"), format_error);
}

TEST_CASE("image: wrong and absurd sizes")
{
    temp_dir dir;
    write_png(dir / "a.png", random_image(23, 9, 2));
    CHECK_THROWS_WITH_AS((void)read_image(dir / "a.png", 9, 23), doctest::Contains("size 23x9 (width x height), expected 9x23"),
                         shape_error);

    // A BMP header claiming 100000 x 100000 pixels: refused from the header, before decoding.
    std::string bmp = read_file(dir / "a.png");  // placeholder buffer, overwritten below
    write_bmp(dir / "b.bmp", random_image(4, 4, 3));
    bmp = read_file(dir / "b.bmp");
    put_le32(bmp, 18, 100000);
    put_le32(bmp, 22, 100000);
    write_file_atomic(dir / "huge.bmp", bmp);
    CHECK_THROWS_WITH_AS((void)read_image(dir / "huge.bmp"), doctest::Contains("100000x100000 is empty or too large"), shape_error);

    CHECK_THROWS_AS(write_png(dir / "e.png", rgb_image{}), shape_error);
    rgb_image bad = rgb_image::make(4, 4);
    bad.pixels.pop_back();
    CHECK_THROWS_WITH_AS(write_bmp(dir / "bad.bmp", bad), doctest::Contains("holds 47 bytes, expected height*width*3"), shape_error);
    CHECK_FALSE(fs::exists(dir / "bad.bmp"));
}

TEST_CASE("image: random corruption of BMP and PNG files gives an image or a handemo error, never a crash")
{
    temp_dir dir;
    const rgb_image im = random_image(7, 5, 9);
    write_bmp(dir / "a.bmp", im);
    write_png(dir / "a.png", im);
    std::mt19937 rng(4242);
    std::size_t decoded = 0, refused = 0;
    for (const char* name : {"a.bmp", "a.png"}) {
        const std::string good = read_file(dir / name);
        for (int it = 0; it < 1500; ++it) {
            std::string s = good;
            for (int e = 0; e < 1 + static_cast<int>(rng() % 4); ++e) s[rng() % s.size()] = static_cast<char>(rng() & 0xFF);
            if (rng() % 4 == 0) s.resize(rng() % s.size());
            try {
                const rgb_image r = decode_image(s, name);
                CHECK(r.pixels.size() == r.width * r.height * 3);
                ++decoded;
            } catch (const handemo::error&) {
                ++refused;
            }
        }
    }
    MESSAGE("image corruption: " << decoded << " decoded, " << refused << " refused");
    CHECK(refused > 0);
}
