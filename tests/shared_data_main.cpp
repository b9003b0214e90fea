// The doctest main of the test programs that read the shared data set (../shared/data: the Bandai and
// Xia BVH files, HANDEMO_SHARED_DIR). Without it they cannot run, and that is reported as a skip, not a
// pass or a failure: the program prints why and exits 77, which CTest's SKIP_RETURN_CODE turns into
// "Skipped" (label shared-data). CI has the data and runs them. HANDEMO_TEST_NO_SHARED_DATA=1 in the
// environment makes the data count as absent (the test of the skip itself uses it).
#define DOCTEST_CONFIG_IMPLEMENT
#include <doctest/doctest.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <system_error>

int main(int argc, char** argv)
{
    const std::filesystem::path data = std::filesystem::path(HANDEMO_SHARED_DIR) / "data";
    const char* pretend = std::getenv("HANDEMO_TEST_NO_SHARED_DATA");
    std::error_code ec;
    if ((pretend && std::strcmp(pretend, "1") == 0) || !std::filesystem::is_directory(data, ec)) {
        std::printf("shared data not found at %s: skipped (exit 77)\n", data.string().c_str());
        return 77;
    }
    doctest::Context context(argc, argv);
    const int rc = context.run();
    return rc == 77 ? 1 : rc;  // never let a failure read as a skip
}
