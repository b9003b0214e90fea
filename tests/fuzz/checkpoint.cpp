// Fuzz target: StarGAN checkpoints. The checksum is recomputed before parse_checkpoint (as a hostile file
// would do), so the fuzzer reaches the metadata checks, load_model's checks against the configuration
// and one generator run per domain of an accepted model.
#include "fuzz.hpp"

#include <handemo/stargan/transfer.hpp>

namespace handemo_fuzz::checkpoint {

inline int run(const std::uint8_t* data, std::size_t size)
{
    return refuse_ok([&] {
        handemo::safetensors_file f = handemo::parse_safetensors(as_text(data, size), "fuzz-checkpoint.safetensors");
        if (f.metadata.contains("checksum")) f.metadata["checksum"] = handemo::stargan::detail::checkpoint_checksum(f);
        const auto [file, info] = handemo::stargan::parse_checkpoint(std::move(f));
        const auto model = handemo::stargan::load_model(file, info);
        handemo::network_image<handemo::dynamic_keyframes> net;
        net.count_ = model->keyframes();
        net.joints = model->joints();
        net.data.assign(3 * model->keyframes() * model->joints(), 0.f);
        for (std::size_t d = 0; d < model->info().domains.size(); ++d) {
            refuse_ok([&] { (void)model->generate(net, d); });
            (void)model->tempo(model->info().domains[d]);
            (void)model->amplitude(model->info().domains[d]);
        }
    });
}

}  // namespace handemo_fuzz::checkpoint

HANDEMO_FUZZ_ENTRY(checkpoint)
