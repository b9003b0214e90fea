// The glove subcommands (list, record, calibrate, live, simulate, send) in their own translation unit: the only
// one of the CLI that includes <handemo/glove.hpp>, and <handemo/glove/hid.hpp> (hidapi) when the
// handemo::glove target exists (HANDEMO_HAVE_HIDAPI, examples/CMakeLists.txt).
#include "registry.hpp"

#include "glove/common.hpp"
#include "glove/list.hpp"
#include "glove/record.hpp"
#include "glove/calibrate.hpp"
#include "glove/simulate.hpp"
#include "glove/live.hpp"
#include "glove/send.hpp"

static handemo::cli::add_command reg_glove{85, [](CLI::App& app) {
    auto* glove = app.add_subcommand("glove", "Capture hand motion with a data glove (Senso, OpenGloves, 5DT, HID profiles): list, record, calibrate, live transfer, simulate, send");
    glove->require_subcommand(1);
    handemo::cli::glove_cmd::add_list(glove);
    handemo::cli::glove_cmd::add_record(glove);
    handemo::cli::glove_cmd::add_calibrate(glove);
    handemo::cli::glove_cmd::add_live(glove);
    handemo::cli::glove_cmd::add_simulate(glove);
    handemo::cli::glove_cmd::add_send(glove);
}};
