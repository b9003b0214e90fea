// The StarGAN subcommands (train, transfer, demo, eval, export) in one translation unit: each instantiates the trainer
// and the generator for every named configuration, and compiling those once instead of once per
// subcommand halves the CLI's build time.
#include "registry.hpp"
#include "stargan/options.hpp"

#include "stargan/train.hpp"
#include "stargan/transfer.hpp"
#include "stargan/demo.hpp"
#include "stargan/eval.hpp"
#include "stargan/export.hpp"

namespace handemo::cli {
/// For `handemo glove live` (cmd_glove.cpp), so that the glove's translation unit does not compile every
/// generator configuration again.
std::unique_ptr<stargan::emotion_model> load_emotion_model(const std::filesystem::path& path) { return stargan::load_model(path); }
}  // namespace handemo::cli
