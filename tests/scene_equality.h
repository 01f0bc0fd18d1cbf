// Field-by-field scene equality for the scene and built-in tests.
#pragma once

#include <gtest/gtest.h>

#include <string>

#include "models/scene.h"

namespace springlab::testing {

inline void expect_same_scene(const Scene& a, const Scene& b) {
  EXPECT_EQ(a.name, b.name);
  EXPECT_EQ(a.dimension, b.dimension);
  EXPECT_EQ(a.gravity, b.gravity);
  EXPECT_EQ(a.drag, b.drag);
  ASSERT_EQ(a.wind.has_value(), b.wind.has_value());
  if (a.wind) {
    EXPECT_EQ(a.wind->velocity, b.wind->velocity);
    EXPECT_EQ(a.wind->coefficient, b.wind->coefficient);
    EXPECT_EQ(a.wind->gust, b.wind->gust);
    EXPECT_EQ(a.wind->frequency, b.wind->frequency);
  }
  ASSERT_EQ(a.particles.size(), b.particles.size());
  for (std::size_t p = 0; p < a.particles.size(); ++p) {
    SCOPED_TRACE("particle " + std::to_string(p));
    EXPECT_EQ(a.particles[p].x, b.particles[p].x);
    EXPECT_EQ(a.particles[p].v, b.particles[p].v);
    EXPECT_EQ(a.particles[p].mass, b.particles[p].mass);
    EXPECT_EQ(a.particles[p].fixed, b.particles[p].fixed);
  }
  ASSERT_EQ(a.springs.size(), b.springs.size());
  for (std::size_t s = 0; s < a.springs.size(); ++s) {
    SCOPED_TRACE("spring " + std::to_string(s));
    EXPECT_EQ(a.springs[s].i, b.springs[s].i);
    EXPECT_EQ(a.springs[s].j, b.springs[s].j);
    EXPECT_EQ(a.springs[s].k, b.springs[s].k);
    EXPECT_EQ(a.springs[s].rest, b.springs[s].rest);
    EXPECT_EQ(a.springs[s].damping, b.springs[s].damping);
  }
}

}  // namespace springlab::testing
