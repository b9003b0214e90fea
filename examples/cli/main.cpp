// handemo: the command-line front end. Subcommands are headers under motion/, render/ and stargan/, compiled
// in cmd_motion.cpp, cmd_render.cpp and cmd_stargan.cpp; errors print one line and exit 1.
#include "build_info.hpp"
#include "registry.hpp"

#include <handemo/core/error.hpp>

#include <algorithm>
#include <exception>
#include <iostream>
#include <string>

int main(int argc, char** argv)
{
    CLI::App app{"handemo: change the emotion of captured 3D hand and body motion (StarGAN)", "handemo"};
    app.require_subcommand(1);
    app.set_version_flag("--version", std::string("handemo 0.1.0 (commit ") + handemo::cli::build_commit() + ")");
    // usage errors in the same one-line form as every other error
    app.failure_message([](const CLI::App*, const CLI::Error& e) {
        return "handemo: error: " + std::string(e.what()) + " (see --help)\n";
    });
    auto& reg = handemo::cli::registry();
    std::stable_sort(reg.begin(), reg.end(), [](auto& a, auto& b) { return a.first < b.first; });
    for (auto& [order, add] : reg) add(app);
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        // app.exit prints --help / --version (code 0) or the one-line usage error; CLI11's own codes
        // (106 required option missing, 109 extra arguments, ...) become 1, as every other failure.
        return app.exit(e) == 0 ? 0 : 1;
    } catch (const std::exception& e) {
        std::cerr << "handemo: error: " << e.what() << "\n";
        if (const auto& mpi = handemo::cli::mpi(); mpi.abort) mpi.abort();  // `train --mpi`: end the other processes too
        return 1;
    }
    return 0;
}
