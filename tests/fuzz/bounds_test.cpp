// Resource bounds on hostile sizes: each input is refused with a handemo error naming the file, in a
// child process whose address space is capped at 256 MB above what it had at fork (so an allocation sized
// from a hostile header fails as bad_alloc, which the test reports), and whose peak resident memory
// (wait4's ru_maxrss) must stay under 256 MB.
#include <doctest/doctest.h>
#include <handemo/image/io.hpp>
#include <handemo/motion/bvh.hpp>
#include <handemo/nn/safetensors.hpp>

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

using namespace handemo;

namespace {

constexpr long limit_mb = 256;

long vm_size_kb()
{
    std::ifstream in("/proc/self/status");
    std::string line;
    while (std::getline(in, line))
        if (line.rfind("VmSize:", 0) == 0) return std::atol(line.c_str() + 7);
    return 0;
}

/// Runs `f` in a child with RLIMIT_AS = current size + 256 MB; requires a handemo error whose message
/// contains `expected`, and a peak RSS under 256 MB.
void refused_within_bounds(const std::function<void()>& f, const std::string& expected)
{
    int fd[2];
    REQUIRE(pipe(fd) == 0);
    std::fflush(nullptr);
    const pid_t pid = fork();
    REQUIRE(pid >= 0);
    if (pid == 0) {
        close(fd[0]);
        const rlim_t cap = static_cast<rlim_t>(vm_size_kb() + limit_mb * 1024) * 1024;
        const rlimit rl{cap, cap};
        setrlimit(RLIMIT_AS, &rl);
        std::string msg;
        int code = 0;
        try {
            f();
            msg = "accepted";
            code = 2;
        } catch (const handemo::error& e) {
            msg = e.what();
            code = msg.find(expected) != std::string::npos ? 0 : 3;
        } catch (const std::exception& e) {
            msg = std::string("non-handemo exception: ") + e.what();
            code = 4;
        }
        (void)!write(fd[1], msg.data(), msg.size());
        _exit(code);
    }
    close(fd[1]);
    std::string msg;
    char buf[4096];
    for (ssize_t n; (n = read(fd[0], buf, sizeof buf)) > 0;) msg.append(buf, static_cast<std::size_t>(n));
    close(fd[0]);
    int st = 0;
    rusage ru{};
    REQUIRE(wait4(pid, &st, 0, &ru) == pid);
    INFO("expected: " << expected);
    INFO("message: " << msg);
    INFO("peak RSS: " << ru.ru_maxrss / 1024 << " MB");
    REQUIRE(WIFEXITED(st));
    CHECK(WEXITSTATUS(st) == 0);
    CHECK(ru.ru_maxrss < limit_mb * 1024);
}

const std::string tiny_bvh = R"(HIERARCHY
ROOT Hips
{
	OFFSET 0 0 0
	CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
	JOINT Left_Arm
	{
		OFFSET 0 1 0
		CHANNELS 3 Zrotation Xrotation Yrotation
		End Site
		{
			OFFSET 0 0.5 0
		}
	}
}
MOTION
Frames:	2
Frame Time:	0.0333333
1 2 3 4 5 6 7 8 9
-1 -2 -3 -4 -5 -6 -7 -8 -9.25
)";

std::string nested_bvh(std::size_t depth)
{
    std::string s = "HIERARCHY\nROOT j0\n{\nOFFSET 0 0 0\nCHANNELS 3 Zrotation Xrotation Yrotation\n";
    for (std::size_t i = 1; i < depth; ++i)
        s += "JOINT j" + std::to_string(i) + "\n{\nOFFSET 0 1 0\nCHANNELS 3 Zrotation Xrotation Yrotation\n";
    s += "End Site\n{\nOFFSET 0 1 0\n}\n";
    for (std::size_t i = 0; i < depth; ++i) s += "}\n";
    s += "MOTION\nFrames: 1\nFrame Time: 0.01\n";
    for (std::size_t i = 0; i < depth; ++i) s += "0 0 0 ";
    s += "\n";
    return s;
}

void put_be32(std::string& s, std::uint32_t v)
{
    for (int k = 3; k >= 0; --k) s += static_cast<char>((v >> (8 * k)) & 0xFF);
}

std::string png_chunk(const std::string& type, const std::string& body)
{
    std::string c;
    put_be32(c, static_cast<std::uint32_t>(body.size()));
    c += type + body;
    put_be32(c, handemo::detail::crc32(type + body));
    return c;
}

std::string png_ihdr(std::uint32_t w, std::uint32_t h)
{
    std::string b;
    put_be32(b, w);
    put_be32(b, h);
    b += std::string("\x08\x02\x00\x00\x00", 5);
    return png_chunk("IHDR", b);
}

/// A zlib stream (fixed Huffman) inflating to `n` zero bytes (n - 1 a multiple of 258), with a wrong
/// Adler-32: one literal, then matches of length 258 at distance 1, 13 bits per 258 bytes.
std::string zlib_zeros(std::size_t n)
{
    std::string out = "\x78\x01";
    std::uint64_t acc = 0;
    int bits = 0;
    auto put = [&](std::uint32_t v, int len) {  // v's bits, least significant first
        acc |= static_cast<std::uint64_t>(v) << bits;
        bits += len;
        while (bits >= 8) {
            out += static_cast<char>(acc & 0xFF);
            acc >>= 8;
            bits -= 8;
        }
    };
    auto code = [&](std::uint32_t c, int len) {  // a Huffman code, most significant bit first
        std::uint32_t r = 0;
        for (int i = 0; i < len; ++i) r |= ((c >> i) & 1u) << (len - 1 - i);
        put(r, len);
    };
    put(1, 1);          // final block
    put(1, 2);          // fixed Huffman
    code(0x30, 8);      // literal 0
    for (std::size_t k = 0; k < (n - 1) / 258; ++k) {
        code(0xC5, 8);  // length symbol 285 (258)
        code(0, 5);     // distance code 0 (1)
    }
    code(0, 7);         // end of block
    if (bits) put(0, 8 - bits);
    out += std::string(4, '\0');
    return out;
}

const std::string png_signature("\x89PNG\r\n\x1a\n", 8);

std::string bmp(std::uint32_t w, std::int32_t h, unsigned bpp, std::uint32_t compression, std::size_t pixel_bytes)
{
    std::string s = "BM";
    auto le32 = [&](std::uint32_t v) {
        for (int k = 0; k < 4; ++k) s += static_cast<char>((v >> (8 * k)) & 0xFF);
    };
    const std::uint32_t palette = bpp <= 8 ? 4u << bpp : 0;
    le32(static_cast<std::uint32_t>(54 + palette + pixel_bytes));
    le32(0);
    le32(54 + palette);
    le32(40);
    le32(w);
    le32(static_cast<std::uint32_t>(h));
    s += static_cast<char>(1), s += '\0';
    s += static_cast<char>(bpp), s += '\0';
    le32(compression);
    le32(static_cast<std::uint32_t>(pixel_bytes));
    le32(2835), le32(2835), le32(bpp <= 8 ? 1u << bpp : 0), le32(0);
    for (std::uint32_t i = 0; i < palette / 4; ++i) s += std::string{static_cast<char>(i), static_cast<char>(i), static_cast<char>(i), '\0'};
    return s + std::string(pixel_bytes, '\x40');
}

}  // namespace

TEST_CASE("BVH: Frames: 2000000000 and 100 000 nested JOINTs are refused before allocating, deep nesting parses")
{
    std::string big = tiny_bvh;
    big.replace(big.find("Frames:\t2"), 9, "Frames:\t2000000000");
    refused_within_bounds([&] { (void)parse_bvh(big, "big.bvh"); }, "big.bvh:17: Frames: 2000000000 but the file has 2 data rows");
    const std::string deep = nested_bvh(100000);
    refused_within_bounds([&] { (void)parse_bvh(deep, "deep.bvh"); }, "deep.bvh:");
    refused_within_bounds([&] { (void)parse_bvh(deep, "deep.bvh"); }, "more than 10000 joints");
    // 9 999 nested joints (the limit) parse and write back without recursion.
    const clip c = parse_bvh(nested_bvh(9999), "deep9999.bvh");
    CHECK(c.skel.size() == 9999);
    CHECK(parse_bvh(to_bvh_string(c), "again.bvh").skel.size() == 9999);
}

TEST_CASE("safetensors: a shape of 1e9 elements and an 80 MB header are refused before allocating")
{
    auto file = [](const std::string& header, const std::string& data) {
        std::string s(8, '\0');
        std::uint64_t n = header.size();
        std::memcpy(s.data(), &n, 8);
        return s + header + data;
    };
    const std::string huge_shape = file(R"({"w":{"dtype":"F32","shape":[1000000000],"data_offsets":[0,4000000000]}})", "");
    refused_within_bounds([&] { (void)parse_safetensors(huge_shape, "huge.safetensors"); }, "huge.safetensors: tensor w: data_offsets end 4000000000 is beyond");
    const std::string lying_shape = file(R"({"w":{"dtype":"F32","shape":[1000000000],"data_offsets":[0,4]}})", "abcd");
    refused_within_bounds([&] { (void)parse_safetensors(lying_shape, "lying.safetensors"); }, "lying.safetensors: tensor w: shape [1000000000] of F32 needs 4000000000 bytes");
    const std::string big_header = file(std::string(80'000'000, ' '), "");
    refused_within_bounds([&] { (void)parse_safetensors(big_header, "big.safetensors"); }, "big.safetensors: header length 80000000 exceeds the 4194304-byte limit");
    // The largest header accepted, made of the smallest JSON values (the worst case for nlohmann's tree).
    std::string zeros = "[0";
    while (zeros.size() + 3 < safetensors_max_header) zeros += ",0";
    zeros += "]";
    refused_within_bounds([&] { (void)parse_safetensors(file(zeros, ""), "zeros.safetensors"); }, "zeros.safetensors: header is a JSON array");
    std::string nested(1'000'000, '[');
    refused_within_bounds([&] { (void)parse_safetensors(file(nested, ""), "nested.safetensors"); }, "nested.safetensors: header nests JSON deeper");
}

TEST_CASE("PNG: a 60000 x 60000 header, a zlib bomb and bad CRC or Adler-32 are refused")
{
    const std::string iend = png_chunk("IEND", "");
    const std::string huge = png_signature + png_ihdr(60000, 60000) + png_chunk("IDAT", zlib_zeros(259)) + iend;
    refused_within_bounds([&] { (void)decode_image(huge, "huge.png"); }, "huge.png: size 60000x60000 is empty or too large");
    // 16 x 16 declared (784 bytes of scanlines), 400 MB inflated.
    const std::string bomb = png_signature + png_ihdr(16, 16) + png_chunk("IDAT", zlib_zeros(1 + 258 * 1'550'000)) + iend;
    CHECK(bomb.size() < 3'000'000);
    refused_within_bounds([&] { (void)decode_image(bomb, "bomb.png"); }, "bomb.png: corrupt or truncated PNG: IDAT stream is corrupt or does not decompress to the 784 bytes");

    // A valid 2 x 2 image, then the same with one flipped bit in a chunk, and with a wrong Adler-32.
    const std::string rows("\0\1\2\3\4\5\6\0\7\10\11\12\13\14", 14);
    std::string z = "\x78\x01";  // stored block
    z += std::string("\x01\x0e\x00\xf1\xff", 5) + rows;
    std::string adler;
    put_be32(adler, handemo::detail::adler32(reinterpret_cast<const unsigned char*>(rows.data()), rows.size()));
    const std::string good = png_signature + png_ihdr(2, 2) + png_chunk("IDAT", z + adler) + iend;
    const rgb_image im = decode_image(good, "good.png");
    CHECK(im.pixels == std::vector<std::uint8_t>{1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12});
    std::string flipped = good;
    flipped[flipped.size() - 20] ^= 0x01;  // inside IDAT
    refused_within_bounds([&] { (void)decode_image(flipped, "flipped.png"); }, "flipped.png: corrupt or truncated PNG: CRC mismatch in chunk 'IDAT'");
    const std::string bad_adler = png_signature + png_ihdr(2, 2) + png_chunk("IDAT", z + std::string(4, '\x11')) + iend;
    refused_within_bounds([&] { (void)decode_image(bad_adler, "adler.png"); }, "adler.png: corrupt or truncated PNG: Adler-32 mismatch");
}

TEST_CASE("BMP: truncated files of any compression or depth and palette BMPs are refused")
{
    refused_within_bounds([&] { (void)decode_image(bmp(4, 4, 24, 0, 0), "empty24.bmp"); }, "empty24.bmp: truncated BMP");
    refused_within_bounds([&] { (void)decode_image(bmp(4, 4, 32, 0, 20), "short32.bmp"); }, "short32.bmp: truncated BMP");
    refused_within_bounds([&] { (void)decode_image(bmp(4, -4, 24, 0, 47), "topdown.bmp"); }, "topdown.bmp: truncated BMP");
    refused_within_bounds([&] { (void)decode_image(bmp(4, 4, 24, 0xFFFFFFFFu, 0), "negative.bmp"); }, "negative.bmp: BMP with a 40-byte header, 24 bits per pixel and compression 4294967295");
    refused_within_bounds([&] { (void)decode_image(bmp(4, 4, 8, 0, 16), "palette.bmp"); }, "palette.bmp: BMP with a 40-byte header, 8 bits per pixel");
    refused_within_bounds([&] { (void)decode_image(bmp(4, 4, 8, 1, 4), "rle8.bmp"); }, "rle8.bmp:");
    const rgb_image im = decode_image(bmp(4, 4, 24, 0, 48), "full.bmp");
    CHECK(im.width == 4);
    CHECK(im.pixels.size() == 48);
}
