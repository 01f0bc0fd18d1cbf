// Field-by-field scene equality for the scene and built-in tests: the
// particles and the blocks of the kinds registered today field by field,
// and every block (of any kind) through its scene file text, which holds
// each number in its shortest round-trip form.
#pragma once

#include <gtest/gtest.h>

#include <string>

#include "models/springs/drag.h"
#include "models/springs/gravity.h"
#include "models/core/scene.h"
#include "models/springs/springs.h"
#include "models/springs/wind.h"
#include "models/model/scene_file.h"

namespace springlab::testing {

inline void expect_same_scene(const Scene& a, const Scene& b) {
  EXPECT_EQ(scene_to_json(a), scene_to_json(b));
  EXPECT_EQ(a.name, b.name);
  EXPECT_EQ(a.dimension, b.dimension);
  EXPECT_EQ(a.get<Gravity>().acceleration, b.get<Gravity>().acceleration);
  EXPECT_EQ(a.get<Drag>().gamma, b.get<Drag>().gamma);
  ASSERT_EQ(a.has<Wind>(), b.has<Wind>());
  if (a.has<Wind>()) {
    EXPECT_EQ(a.find<Wind>()->velocity, b.find<Wind>()->velocity);
    EXPECT_EQ(a.find<Wind>()->coefficient, b.find<Wind>()->coefficient);
    EXPECT_EQ(a.find<Wind>()->gust, b.find<Wind>()->gust);
    EXPECT_EQ(a.find<Wind>()->frequency, b.find<Wind>()->frequency);
  }
  ASSERT_EQ(a.particles.size(), b.particles.size());
  for (std::size_t p = 0; p < a.particles.size(); ++p) {
    SCOPED_TRACE("particle " + std::to_string(p));
    EXPECT_EQ(a.particles[p].x, b.particles[p].x);
    EXPECT_EQ(a.particles[p].v, b.particles[p].v);
    EXPECT_EQ(a.particles[p].mass, b.particles[p].mass);
    EXPECT_EQ(a.particles[p].fixed, b.particles[p].fixed);
    EXPECT_EQ(a.particles[p].X, b.particles[p].X);
  }
  ASSERT_EQ(a.get<Springs>().size(), b.get<Springs>().size());
  for (std::size_t s = 0; s < a.get<Springs>().size(); ++s) {
    SCOPED_TRACE("spring " + std::to_string(s));
    EXPECT_EQ(a.get<Springs>()[s].i, b.get<Springs>()[s].i);
    EXPECT_EQ(a.get<Springs>()[s].j, b.get<Springs>()[s].j);
    EXPECT_EQ(a.get<Springs>()[s].k, b.get<Springs>()[s].k);
    EXPECT_EQ(a.get<Springs>()[s].rest, b.get<Springs>()[s].rest);
    EXPECT_EQ(a.get<Springs>()[s].damping, b.get<Springs>()[s].damping);
  }
}

}  // namespace springlab::testing
