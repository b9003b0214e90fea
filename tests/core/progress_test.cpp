#include <doctest/doctest.h>
#include <handemo/core/progress.hpp>

#include <cstdio>
#include <string>

TEST_CASE("format_duration")
{
    CHECK(handemo::format_duration(5) == "5s");
    CHECK(handemo::format_duration(185) == "3m05s");
    CHECK(handemo::format_duration(3720) == "1h02m");
    CHECK(handemo::format_duration(-1) == "--");
}

TEST_CASE("progress writes plain lines with an ETA when not on a terminal")
{
    std::FILE* f = std::tmpfile();
    REQUIRE(f);
    {
        handemo::progress p("train", 4, f, 0.0);
        for (long i = 1; i <= 4; ++i) p.update(i, "loss 1.0");
    }
    std::rewind(f);
    std::string all;
    char buf[256];
    while (std::fgets(buf, sizeof buf, f)) all += buf;
    std::fclose(f);
    CHECK(all.find("train 1/4 (25%)") != std::string::npos);
    CHECK(all.find("train 4/4 (100%)") != std::string::npos);
    CHECK(all.find("ETA") != std::string::npos);
    CHECK(all.find("loss 1.0") != std::string::npos);
}
