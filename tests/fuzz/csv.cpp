// Fuzz target: CSV motion text (parse_csv) against a fixed two-joint skeleton (tests/formats/data/tiny.bvh).
#include "fuzz.hpp"

#include <handemo/motion/bvh.hpp>
#include <handemo/motion/csv.hpp>

namespace handemo_fuzz::csv {

inline const handemo::skeleton& reference()
{
    static const handemo::skeleton s = handemo::parse_bvh(R"(HIERARCHY
ROOT Hips
{
	OFFSET 0 0 0
	CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
	JOINT Left_Arm
	{
		OFFSET 0 1 0
		CHANNELS 3 Zrotation Xrotation Yrotation
		End Site
		{
			OFFSET 0 0.5 0
		}
	}
}
MOTION
Frames:	1
Frame Time:	0.0333333
1 2 3 4 5 6 7 8 9
)", "tiny.bvh").skel;
    return s;
}

inline int run(const std::uint8_t* data, std::size_t size)
{
    const handemo::skeleton& skel = reference();
    return refuse_ok([&] {
        const handemo::clip c = handemo::parse_csv(as_text(data, size), "fuzz.csv", skel);
        c.validate("fuzz.csv");
        (void)handemo::parse_csv(handemo::to_csv_string(c), "fuzz-roundtrip.csv", skel);
    });
}

}  // namespace handemo_fuzz::csv

HANDEMO_FUZZ_ENTRY(csv)
