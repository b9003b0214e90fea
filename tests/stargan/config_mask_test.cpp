// HANDEMO_CONFIG_MASK (stargan/configs.hpp): test_stargan compiles hand-embedded, body-embedded and hand-tiny only
// (tests/stargan/CMakeLists.txt), and with_config() refuses the two it leaves out by name, which a model
// checkpoint of either configuration reaches through load_model().
#include <doctest/doctest.h>
#include <handemo/stargan/configs.hpp>

#include <string>

using namespace handemo;

TEST_CASE("a program compiled with fewer configurations refuses the others by name (HANDEMO_CONFIG_MASK)")
{
    static_assert(stargan::compiled_configs == 21, "test_stargan compiles hand-embedded, body-embedded, hand-tiny");
    const auto name = []<stargan::stargan_config C>(const stargan::config_info& i) { return i.name + ":" + std::to_string(C::joints); };
    CHECK(stargan::with_config("hand-tiny", name) == "hand-tiny:23");
    CHECK(stargan::with_config("hand-embedded", name) == "hand-embedded:23");
    CHECK(stargan::with_config("body-embedded", name).rfind("body-embedded:", 0) == 0);
    CHECK_THROWS_WITH_AS(stargan::with_config("hand-paper", name),
                         "config: configuration 'hand-paper' is not compiled into this program (HANDEMO_CONFIG_MASK 21 leaves out bit 2)",
                         value_error);
    CHECK_THROWS_WITH_AS(stargan::with_config("hand-micro", name), doctest::Contains("leaves out bit 8"), value_error);
    CHECK_THROWS_WITH_AS(stargan::with_config("hand-big", name), doctest::Contains("unknown configuration 'hand-big'"), value_error);
}
