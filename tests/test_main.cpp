// The one doctest main shared by every test program.
// Test cases that read the shared data set (../shared/data: the Bandai and Xia BVH files, HANDEMO_SHARED_DIR)
// are in the doctest test suite "shared-data" (each such file opens it with TEST_SUITE_BEGIN), inside the
// program of their module, so that they are compiled with its other cases instead of in a program of their own.
//   <program> [doctest options]                  every case except the shared-data suite
//   <program> --shared-data [doctest options]    only the shared-data suite; without the data the program prints
//                                                why and exits 77, which CTest's SKIP_RETURN_CODE reports as
//                                                "Skipped" (label shared-data), never as a pass or a failure
// HANDEMO_TEST_NO_SHARED_DATA=1 in the environment makes the data count as absent (the test of the skip itself
// uses it). A failing run never exits 77.
#define DOCTEST_CONFIG_IMPLEMENT
#include <doctest/doctest.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <system_error>
#include <vector>

int main(int argc, char** argv)
{
    bool shared = false;
    std::vector<char*> args;
    for (int i = 0; i < argc; ++i) {
        if (i > 0 && std::strcmp(argv[i], "--shared-data") == 0) shared = true;
        else args.push_back(argv[i]);
    }
    if (shared) {
        const std::filesystem::path data = std::filesystem::path(HANDEMO_SHARED_DIR) / "data";
        const char* pretend = std::getenv("HANDEMO_TEST_NO_SHARED_DATA");
        std::error_code ec;
        if ((pretend && std::strcmp(pretend, "1") == 0) || !std::filesystem::is_directory(data, ec)) {
            std::printf("shared data not found at %s: skipped (exit 77)\n", data.string().c_str());
            return 77;
        }
    }
    doctest::Context context(static_cast<int>(args.size()), args.data());
    context.addFilter(shared ? "test-suite" : "test-suite-exclude", "shared-data");
    const int rc = context.run();
    if (context.shouldExit()) return rc;
    return rc == 77 ? 1 : rc;  // never let a failure read as a skip
}
