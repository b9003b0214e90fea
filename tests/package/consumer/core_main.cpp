// Consumer of the core target only (no stb anywhere on its include path): a BVH round trip.
#include <handemo/motion.hpp>

#include <cstdio>

int main()
{
    handemo::skeleton sk;
    sk.joints.resize(1);
    sk.joints[0].name = "root";
    handemo::clip c = handemo::clip::make(sk, 2, 30);
    c.angle(1, 0, 2) = -12.25;
    const handemo::clip r = handemo::parse_bvh(handemo::to_bvh_string(c), "core.bvh");
    if (r.frames != 2 || r.angle(1, 0, 2) != -12.25) {
        std::puts("core consumer: BVH round trip failed");
        return 1;
    }
    std::puts("core consumer: ok");
    return 0;
}
