#include "fixture.hpp"

#include <handemo/nn/safetensors.hpp>

#include <map>
#include <mutex>

namespace handemo::test {

const safetensors_file& fixture(const std::string& name)
{
    static std::mutex m;
    static std::map<std::string, safetensors_file> cache;
    std::lock_guard<std::mutex> lock(m);
    auto it = cache.find(name);
    if (it == cache.end())
        it = cache.emplace(name, read_safetensors(std::string(HANDEMO_FIXTURE_DIR) + "/" + name)).first;
    return it->second;
}

}  // namespace handemo::test
