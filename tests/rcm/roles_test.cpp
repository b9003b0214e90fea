// Joint roles from names (Bandai, Xia/CMU, Mixamo, the 23-joint hand), overrides and missing-role errors.
#include "helpers.hpp"

#include <handemo/motion.hpp>

#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>

using namespace handemo;
using handemo::rcm::role;

namespace {
std::string role_name(const rcm::role_map& m, role r) { return m.points[m.at(r)]; }
}  // namespace

TEST_CASE("roles: Bandai names")
{
    const auto m = rcm::find_roles(std::vector<std::string>{"joint_Root", "Hips", "Spine", "Chest", "Neck", "Head", "Shoulder_L", "UpperArm_L",
                                                            "LowerArm_L", "Hand_L", "Shoulder_R", "UpperArm_R", "LowerArm_R", "Hand_R",
                                                            "UpperLeg_L", "LowerLeg_L", "Foot_L", "Toes_L", "UpperLeg_R", "LowerLeg_R", "Foot_R", "Toes_R"});
    m.require(rcm::feature_set::body);
    CHECK(role_name(m, role::pelvis) == "Hips");
    CHECK(role_name(m, role::chest) == "Chest");
    CHECK(role_name(m, role::left_shoulder) == "UpperArm_L");
    CHECK(role_name(m, role::right_elbow) == "LowerArm_R");
    CHECK(role_name(m, role::left_hip) == "UpperLeg_L");
    CHECK(role_name(m, role::right_knee) == "LowerLeg_R");
    CHECK(role_name(m, role::right_foot) == "Foot_R");
    CHECK(rcm::detect_feature_set(m) == rcm::feature_set::body);
}

TEST_CASE("roles: Xia / CMU and Mixamo names")
{
    const auto x = rcm::find_roles(std::vector<std::string>{"Hips", "LHipJoint", "LeftUpLeg", "LeftLeg", "LeftFoot", "LeftToeBase", "RHipJoint",
                                                            "RightUpLeg", "RightLeg", "RightFoot", "LowerBack", "Spine", "Spine1", "Neck", "Neck1",
                                                            "Head", "LeftShoulder", "LeftArm", "LeftForeArm", "LeftHand", "RightShoulder",
                                                            "RightArm", "RightForeArm", "RightHand"});
    x.require(rcm::feature_set::body);
    CHECK(role_name(x, role::chest) == "Spine1");
    CHECK(role_name(x, role::left_shoulder) == "LeftArm");
    CHECK(role_name(x, role::left_hip) == "LeftUpLeg");
    CHECK(role_name(x, role::left_knee) == "LeftLeg");
    CHECK(role_name(x, role::neck) == "Neck");
    const auto mx = rcm::find_roles(std::vector<std::string>{"mixamorig:Hips", "mixamorig:Spine2", "mixamorig:Neck", "mixamorig:Head",
                                                             "mixamorig:LeftArm", "mixamorig:LeftForeArm", "mixamorig:LeftHand"});
    CHECK(role_name(mx, role::chest) == "mixamorig:Spine2");
    CHECK(role_name(mx, role::left_hand) == "mixamorig:LeftHand");
    CHECK_FALSE(mx.has(role::right_hand));
}

TEST_CASE("roles: the 23-joint hand, with fingertips as End Site points")
{
    const auto s = hand_skeleton();
    const auto names = rcm::point_names(s);
    CHECK(names.size() == hand_joint_count + 5);
    const auto m = rcm::find_roles(s);
    m.require(rcm::feature_set::hand);
    CHECK(rcm::detect_feature_set(m) == rcm::feature_set::hand);
    CHECK(role_name(m, role::index_tip) == "index_distal_end");
    CHECK(role_name(m, role::thumb_base) == "thumb_proximal");
    CHECK(role_name(m, role::wrist) == "wrist");
}

TEST_CASE("roles: a missing role is an error naming it; an override file supplies it")
{
    auto names = rcm_test::body_names();
    names[0] = "Skull";  // the head has a name the rules do not know
    const auto m = rcm::find_roles(names);
    CHECK_THROWS_WITH_AS(m.require(rcm::feature_set::body), doctest::Contains("role 'head'"), value_error);
    skeleton s;
    for (std::size_t i = 0; i < names.size(); ++i) s.joints.push_back({names[i], static_cast<int>(i) - 1});
    const auto dir = std::filesystem::temp_directory_path() / "handemo_rcm_roles_test";
    std::filesystem::create_directories(dir);
    std::ofstream(dir / "roles.json") << R"({"roles": {"head": "Skull"}})";
    const auto m2 = rcm::find_roles(s, dir / "roles.json");
    CHECK(m2.points[m2.at(role::head)] == "Skull");
    std::ofstream(dir / "bad.json") << R"({"roles": {"head": "NoSuchJoint"}})";
    CHECK_THROWS_WITH_AS(rcm::find_roles(s, dir / "bad.json"), doctest::Contains("NoSuchJoint"), format_error);
    std::ofstream(dir / "bad_role.json") << R"({"roles": {"tail": "Skull"}})";
    CHECK_THROWS_WITH_AS(rcm::find_roles(s, dir / "bad_role.json"), doctest::Contains("roles.tail"), format_error);
    std::filesystem::remove_all(dir);
}
