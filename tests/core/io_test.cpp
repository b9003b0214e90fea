#include <doctest/doctest.h>
#include <handemo/core/io.hpp>

#include <filesystem>

namespace fs = std::filesystem;

TEST_CASE("write_file_atomic replaces the whole file and leaves no temporary")
{
    const fs::path dir = fs::temp_directory_path() / "handemo_io_test";
    fs::remove_all(dir);
    const fs::path p = dir / "a.txt";
    handemo::write_file_atomic(p, "first");
    CHECK(handemo::read_file(p) == "first");
    handemo::write_file_atomic(p, "second, longer");
    CHECK(handemo::read_file(p) == "second, longer");
    int n = 0;
    for ([[maybe_unused]] auto& e : fs::directory_iterator(dir)) ++n;
    CHECK(n == 1);
    fs::remove_all(dir);
}

TEST_CASE("read_file names the missing file")
{
    CHECK_THROWS_WITH_AS(handemo::read_file("/nonexistent/handemo.bvh"),
                         doctest::Contains("/nonexistent/handemo.bvh"), handemo::io_error);
}

TEST_CASE("write_file_atomic into an unwritable place throws io_error and keeps the old file")
{
    CHECK_THROWS_AS(handemo::write_file_atomic("/proc/handemo_cannot_write/x", "x"), handemo::io_error);
}
