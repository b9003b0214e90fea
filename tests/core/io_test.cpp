#include <doctest/doctest.h>
#include <handemo/core/io.hpp>

#include <algorithm>
#include <csignal>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include <stdlib.h>
#include <sys/resource.h>
#include <unistd.h>

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

TEST_CASE("write_file_atomic into an unwritable place throws io_error")
{
    CHECK_THROWS_AS(handemo::write_file_atomic("/proc/handemo_cannot_write/x", "x"), handemo::io_error);
}

namespace {
int entries(const fs::path& dir)
{
    int n = 0;
    for ([[maybe_unused]] auto& e : fs::directory_iterator(dir)) ++n;
    return n;
}
}  // namespace

TEST_CASE("write_file_atomic whose write fails keeps the old file and leaves no temporary")
{
    // The write itself fails half-way: the process may not write files larger than 64 bytes
    // (RLIMIT_FSIZE, which binds root too, unlike a read-only directory). A writer that truncated the
    // old file in place would lose it here.
    const fs::path dir = fs::temp_directory_path() / "handemo_io_fail_test";
    fs::remove_all(dir);
    const fs::path p = dir / "model.json";
    handemo::write_file_atomic(p, "old content");
    const std::string big(1 << 20, 'x');

    rlimit saved{};
    REQUIRE(getrlimit(RLIMIT_FSIZE, &saved) == 0);
    const auto old_handler = std::signal(SIGXFSZ, SIG_IGN);  // EFBIG instead of a signal
    rlimit small = saved;
    small.rlim_cur = 64;
    REQUIRE(setrlimit(RLIMIT_FSIZE, &small) == 0);
    std::string what;
    try {
        handemo::write_file_atomic(p, big);
    } catch (const handemo::io_error& e) {
        what = e.what();
    }
    setrlimit(RLIMIT_FSIZE, &saved);
    std::signal(SIGXFSZ, old_handler);

    CHECK(what.find(p.string()) != std::string::npos);  // io_error thrown, naming the file
    CHECK(handemo::read_file(p) == "old content");
    CHECK(entries(dir) == 1);
    fs::remove_all(dir);
}

TEST_CASE("write_file_atomic whose rename fails keeps what was there and leaves no temporary")
{
    // The target is a non-empty directory: the temporary is written, the rename over it fails.
    const fs::path dir = fs::temp_directory_path() / "handemo_io_rename_test";
    fs::remove_all(dir);
    const fs::path p = dir / "out";
    handemo::write_file_atomic(p / "kept.txt", "old content");
    CHECK_THROWS_WITH_AS(handemo::write_file_atomic(p, "new"), doctest::Contains(p.string().c_str()), handemo::io_error);
    CHECK(fs::is_directory(p));
    CHECK(handemo::read_file(p / "kept.txt") == "old content");
    CHECK(entries(dir) == 1);
    fs::remove_all(dir);
}

TEST_CASE("make_directories creates parents and names the folder it cannot create")
{
    const auto base = std::filesystem::temp_directory_path() / "handemo_make_directories_test";
    std::filesystem::remove_all(base);
    handemo::make_directories(base / "a" / "b");
    CHECK(std::filesystem::is_directory(base / "a" / "b"));
    handemo::make_directories(base / "a" / "b");  // exists: nothing to do
    handemo::write_file_atomic(base / "file", "x");
    const auto sub = base / "file" / "sub";
    CHECK_THROWS_WITH_AS(handemo::make_directories(sub), doctest::Contains(("cannot create folder " + sub.string()).c_str()), handemo::io_error);
    std::filesystem::remove_all(base);
}

namespace {
/// A fresh folder of this run's own under the temporary directory, removed with everything in it at the end.
struct scratch_dir {
    fs::path path;
    scratch_dir()
    {
        std::string t = (fs::temp_directory_path() / "handemo_io_status_XXXXXX").string();
        if (!::mkdtemp(t.data())) throw std::runtime_error("mkdtemp failed");
        path = t;
    }
    ~scratch_dir() { fs::remove_all(path); }
};
}  // namespace

TEST_CASE("path_exists, is_folder and regular_files_in answer, and name the path whose status cannot be read")
{
    const scratch_dir d;
    handemo::write_file_atomic(d.path / "a.bvh", "x");
    handemo::make_directories(d.path / "sub");
    fs::create_symlink(d.path / "a.bvh", d.path / "link.bvh");   // a link to a file counts as the file
    fs::create_symlink(d.path / "gone", d.path / "broken.bvh");  // a broken link is no file
    CHECK(handemo::path_exists(d.path / "a.bvh"));
    CHECK(handemo::path_exists(d.path / "sub"));
    CHECK(!handemo::path_exists(d.path / "missing"));
    CHECK(!handemo::path_exists(d.path / "a.bvh" / "below_a_file"));
    CHECK(handemo::is_folder(d.path / "sub"));
    CHECK(!handemo::is_folder(d.path / "a.bvh"));
    CHECK(!handemo::is_folder(d.path / "missing"));
    auto files = handemo::regular_files_in(d.path);
    std::sort(files.begin(), files.end());
    CHECK(files == std::vector<fs::path>{d.path / "a.bvh", d.path / "link.bvh"});

    // a link to itself (ELOOP) and a name longer than any file system takes (ENAMETOOLONG): the standard
    // library's throwing calls raise std::filesystem::filesystem_error here, these raise io_error naming the path
    const fs::path loop = d.path / "loop";
    fs::create_symlink(loop, loop);
    const fs::path too_long = d.path / std::string(300, 'n');
    CHECK_THROWS_AS(static_cast<void>(fs::exists(loop)), fs::filesystem_error);
    CHECK_THROWS_AS(static_cast<void>(fs::is_directory(too_long)), fs::filesystem_error);
    for (const fs::path& p : {loop, too_long, loop / "below"}) {
        CAPTURE(p);
        CHECK_THROWS_WITH_AS(handemo::path_exists(p), doctest::Contains(("cannot read the status of " + p.string()).c_str()), handemo::io_error);
        CHECK_THROWS_WITH_AS(handemo::is_folder(p), doctest::Contains(p.string().c_str()), handemo::io_error);
        CHECK_THROWS_WITH_AS(handemo::regular_files_in(p), doctest::Contains(("cannot list the folder " + p.string()).c_str()), handemo::io_error);
    }
    // a folder holding the loop cannot be listed as files: its entry's status cannot be read
    CHECK_THROWS_WITH_AS(handemo::regular_files_in(d.path), doctest::Contains(loop.string().c_str()), handemo::error);
    CHECK_THROWS_WITH_AS(handemo::regular_files_in(d.path / "a.bvh"), doctest::Contains((d.path / "a.bvh").string().c_str()), handemo::io_error);
    CHECK_THROWS_AS(handemo::regular_files_in(d.path / "missing"), handemo::io_error);
}
