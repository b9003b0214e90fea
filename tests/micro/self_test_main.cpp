// Runs the self-test embedded in a header written by `handemo export --header` on this machine: G of the
// header's weights on its self_test_input must equal the host's self_test_output within 1e-5. Built with
// -fno-exceptions -fno-rtti, no heap; HANDEMO_MODEL_HEADER names the header, the struct is handemo_model::model.
// Prints one line: "self-test <config> target <domain>: max |this - host| = <n> e-9: ok|FAILED".
#include HANDEMO_MODEL_HEADER
#include <handemo/micro.hpp>

#include <cmath>
#include <cstdio>

using model = handemo_model::model;
using gen = handemo::micro::generator<model>;

static gen::workspace ws;
static float out[3 * gen::K * gen::J];

int main()
{
    gen::infer(model::self_test_input, model::self_test_target, out, ws);
    float worst = 0.f;
    for (std::size_t i = 0; i < 3 * gen::K * gen::J; ++i) worst = std::fmax(worst, std::fabs(out[i] - model::self_test_output[i]));
    const bool ok = worst <= 1e-5f;
    std::printf("self-test %s target %s: max |this - host| = %ld e-9: %s\n", model::config,
                model::domain_names[model::self_test_target], long(worst * 1e9f), ok ? "ok" : "FAILED");
    return ok ? 0 : 1;
}
