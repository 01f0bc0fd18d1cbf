// Element kinds: the unit a scene and a model are extended by. A kind is one
// sort of thing a scene holds that exerts a force: an element joining
// particles (springs, spring dampers; later triangles, tetrahedra, contact
// planes) or a scene-wide force (gravity, drag, wind). Each kind lives in its
// own file (with a header for its block of scene data, if it has one) and
// registers everything the rest of springlab needs of it:
//
//   - its scene file keys, read, checked and written by its own functions,
//     with its own caps on element arrays;
//   - its ForceTerm (force_term.h: energy, force, dF/dx, dF/dv and the
//     definite part of dF/dx for Newton), built from a scene;
//   - the energy column its potential is reported in ("spring", "gravity");
//   - a random instance, from which the shared tests
//     (tests/test_element_kinds.cc) check its force against its energy and
//     its Jacobians against central differences.
//
// Adding a kind: one file (pair) defining an `ElementKind` and one line in
// element_registry.cc. The scene reader and writer, the model, the energy
// report and the shared tests then cover it without further edits.
#pragma once

#include <array>
#include <cstddef>
#include <memory>
#include <random>
#include <string>
#include <string_view>
#include <vector>

#include "models/core/energies.h"
#include "models/core/force_term.h"
#include "models/core/memory_estimate.h"
#include "models/core/scene.h"
#include "models/core/scene_io.h"
#include "models/core/verdict.h"

namespace springlab {

// Builds the kind's term from the scene, or returns nullptr when the scene
// has nothing of this kind (an absent force costs nothing).
using ForceFactory = std::unique_ptr<ForceTerm> (*)(const Scene&, const ParticleOrder&);
// Builds the kind's divergence rule (verdict.h) for one model of the scene,
// or returns nullptr when the scene has nothing it judges.
using RuleFactory = std::unique_ptr<DivergenceRule> (*)(const Scene&, const ParticleOrder&,
                                                        const VerdictScale&);

// One top-level key of a scene file.
struct SceneKey {
  std::string_view name;
  bool required = false;
  // An array of elements ("springs"): at most `cap` of them per scene,
  // checked while the file is read (before the array is complete), by
  // validate_scene, and over all the scenes of an experiment; `count` says
  // how many a scene has. cap 0: not an element array.
  std::size_t cap = 0;
  std::size_t (*count)(const Scene&) = nullptr;
};

// One element as drawn (--vtk, the report's player, the Python module): the
// particles it joins, in scene order: 2 (a line), 3 (a triangle) or 4 (a
// tetrahedron) of `nodes`.
struct Cell {
  int size = 0;
  std::array<int, 4> nodes{};
};

// A point of a kind's elements at the start, for the extent of motion d of
// the energy scale E_s (scene_extent.h): where it is, and whether it can fall.
struct StartPoint {
  Eigen::Vector3d x = Eigen::Vector3d::Zero();
  bool fixed = false;
};

// Unknowns of a kind's own (issue 47 item 3): a kind whose elements move by
// coordinates of their own rather than by the scene's particles (a free
// rigid body's p and A, 12 unknowns: 4 "pseudo-particles" of 3) declares
// them here, and the model places them after the free particles, kinds in
// registry order (ParticleOrder::first_own), fills their start and mass
// from initial_state, and counts them in E_s. Its terms find their first
// unknown with order.first_own(kind name). A fluid needs none: its unknowns
// are its particles', and its changing neighbours are its term's
// pattern_varies() (force_term.h).
struct OwnUnknowns {
  // How many pseudo-particles of `dimension` unknowns the scene's elements
  // add (0: none). nullptr: the kind has no unknowns of its own.
  int (*count)(const Scene& scene) = nullptr;
  // Their initial positions, velocities and masses, count * dimension
  // values each, written from x0, v0, mass (the kind's first slot).
  void (*initial_state)(const Scene& scene, double* x0, double* v0, double* mass) = nullptr;
  // Adds to `sum` the mass they move (a body's mass once, not its
  // inertias), which E_s weighs with gravity and wind as it does the free
  // particles'.
  void (*add_free_mass)(const Scene& scene, double& sum) = nullptr;
  // Appends their elements' points at the start (a body's vertices).
  void (*start_points)(const Scene& scene, std::vector<StartPoint>& out) = nullptr;
  // Why a method that moves one particle at a time (vbd) cannot move them,
  // naming what couples them and what to use instead.
  std::string_view not_per_particle = {};
};

// Which states a random instance may be in (the shared derivative tests).
enum class RandomStates {
  kAny,       // anything the kind allows: stretched and compressed springs, ...
  kDefinite,  // only states where the exact -dF/dx is positive semidefinite
              // (springs stretched), so its definite part must equal it
};

struct ElementKind {
  std::string_view name;  // "spring", "gravity": names the kind in tests and lists

  // Scene file keys. The top-level keys are read in a fixed order: "name",
  // "dimension", the keys of the kinds that do not refer to particles
  // (scene-wide forces, in registry order), "particles", then the keys of the
  // kinds whose elements name particles (in registry order). Messages list
  // the allowed keys, and files are written, in that same order.
  bool refers_to_particles = false;
  std::vector<SceneKey> keys = {};
  // Reads the kind's keys from the top-level object `document` into `scene`
  // (its dimension, and its particles if refers_to_particles, are there
  // already), refusing the first problem in document order.
  void (*read)(const Json& document, const Reporter& r, Scene& scene) = nullptr;
  // Runs the same checks on a built scene (validate_scene: built-in scenes,
  // scenes made in code), with the same messages.
  void (*validate)(const Scene& scene, const Reporter& r) = nullptr;
  // Appends the kind's top-level entries ({key, JSON text of the value}) as
  // scene_to_json writes them; reading them back gives the same scene.
  void (*write)(const Scene& scene, std::vector<std::pair<std::string, std::string>>& entries) =
      nullptr;

  // Unknowns of its own, beside the particles' (none unless declared).
  OwnUnknowns own_unknowns = {};

  // The force. nullptr for a kind that only holds data for others.
  ForceFactory make = nullptr;
  // Where its potential energy is reported; an empty name: it stores none.
  EnergyColumn energy = {};
  // Its term of docs/command-line.md "The command line"'s energy scale E_s per unit of free mass,
  // given the diameter d of the initial positions (gravity: |g| d, wind: |w_max|^2/2).
  double (*energy_scale_per_mass)(const Scene& scene, double diameter) = nullptr;
  // Whether its force can feed energy into the scene (wind): a scene with
  // such a kind is not unforced, and the bodies' energy rule (verdict.h)
  // does not apply to it.
  bool feeds_energy = false;

  // Its divergence rule (verdict.h: fluids, bodies), which the run driver
  // checks after every step beside the energy rule every scene has;
  // nullptr: the energy rule alone judges it (springs, elements).
  RuleFactory divergence_rule = nullptr;
  // That rule in one sentence, "<matter>: <when it has diverged>", for
  // `springlab list` and the docs (beside the rule's code and bounds).
  std::string_view divergence_sentence = {};

  // Adds the kind's parts of the model's memory (memory_estimate.h), from
  // the scene alone: the bytes its term will hold and the Jacobian blocks it
  // will declare, named in the scene's words. nullptr: nothing that counts.
  void (*memory)(const Scene& scene, MemoryEstimate& out) = nullptr;

  // Appends the cells of the kind's elements, in file order. nullptr: the
  // kind joins no particles (gravity) or draws none of its own (spring
  // damping lives on the springs).
  void (*cells)(const Scene& scene, std::vector<Cell>& out) = nullptr;

  // Adds a random instance of the kind to `scene`, whose particles (random
  // positions and velocities, some fixed) are in place; it may give them
  // rest positions but not change their number. For the shared tests.
  void (*add_random)(Scene& scene, std::mt19937& rng, RandomStates states) = nullptr;
};

}  // namespace springlab
