// Where our degrees of freedom live in a MuJoCo model loaded from our URDF: one hinge or slide
// joint per dof, named like the dof. Shared by the MuJoCo checks (inverse dynamics on random
// states, and replaying solved motion files).
#pragma once

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <string>
#include <vector>

namespace spacetime::testing {

struct MujocoDofs {
  std::vector<int> vel;  // index into qvel, qacc, qfrc_* of dof k
  std::vector<int> pos;  // index into qpos of dof k
};

// Looks every dof up by joint name; a missing name fails the calling test (index 0 stands in).
inline MujocoDofs mujocoDofs(const mjModel* m, const std::vector<std::string>& names) {
  MujocoDofs out;
  for (const std::string& name : names) {
    const int j = mj_name2id(m, mjOBJ_JOINT, name.c_str());
    EXPECT_GE(j, 0) << name;
    out.vel.push_back(j >= 0 ? m->jnt_dofadr[j] : 0);
    out.pos.push_back(j >= 0 ? m->jnt_qposadr[j] : 0);
  }
  return out;
}

}  // namespace spacetime::testing
