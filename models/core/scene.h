// The scene: what a scene file (docs/physics.md "Scene files") or a built-in scene (docs/scenes.md
// "Built-in scenes") describes, before any physics is assembled from it. Plain data; the model
// (model.h) turns it into forces and a state, and models/model/scene_file.h reads,
// checks and writes it as a file.
//
// A scene is its particles plus one block of data per element kind it holds
// (models/core/element_kind.h): the springs, the gravity, the drag, the wind, and
// whatever kinds are registered later. Code that builds a scene reaches a
// block by its type, e.g. `scene.block<Springs>().push_back(spring)` or
// `scene.get<Gravity>().acceleration`; the reading, checking and writing of a
// block live in its kind's file, so adding a kind never edits this file.
#pragma once

#include <Eigen/Core>
#include <any>
#include <cstddef>
#include <deque>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace springlab {

// Thrown for every malformed scene; what() is the one line the user sees,
// already prefixed with the file name and the offending element.
class SceneError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct Particle {
  Eigen::Vector3d x = Eigen::Vector3d::Zero();  // components past `dimension` are 0
  Eigen::Vector3d v = Eigen::Vector3d::Zero();
  double mass = 1.0;
  bool fixed = false;
  // The rest (material) position X (docs/physics.md "Finite elements"): where the particle sits in
  // the undeformed object. Absent: x. Springs take their default rest length
  // from it, elements their rest shape.
  std::optional<Eigen::Vector3d> X = std::nullopt;
  const Eigen::Vector3d& rest_position() const { return X ? *X : x; }
};

class Scene {
 public:
  std::string name;
  int dimension = 2;
  std::vector<Particle> particles;

  // The block of type B, created empty (default-constructed) when the scene
  // has none yet: for code that builds a scene. The reference stays valid
  // while blocks are added (not across remove()).
  template <typename B>
  B& block() {
    for (std::any& b : blocks_) {
      if (B* found = std::any_cast<B>(&b)) return *found;
    }
    return *std::any_cast<B>(&blocks_.emplace_back(B{}));
  }
  // The block of type B, or nullptr when the scene has none.
  template <typename B>
  const B* find() const {
    for (const std::any& b : blocks_) {
      if (const B* found = std::any_cast<B>(&b)) return found;
    }
    return nullptr;
  }
  // The block of type B, or an empty one (no springs, zero gravity) when the
  // scene has none.
  template <typename B>
  const B& get() const {
    static const B empty{};
    const B* found = find<B>();
    return found != nullptr ? *found : empty;
  }
  template <typename B>
  bool has() const {
    return find<B>() != nullptr;
  }
  template <typename B>
  void remove() {
    for (auto it = blocks_.begin(); it != blocks_.end(); ++it) {
      if (std::any_cast<B>(&*it) != nullptr) {
        blocks_.erase(it);
        return;
      }
    }
  }

 private:
  // One per kind present, in the order they were added (which nothing
  // depends on: reading, checking and writing follow the kind registry). A
  // deque: adding a block moves none of the others.
  std::deque<std::any> blocks_;
};

// Resource caps (docs/reliability.md, "Reliability"): a scene larger than this is refused
// before it is built, so a typo like n=100000 is a message, not an
// out-of-memory kill. The largest scene they allow (a 578 x 578 cloth, or a
// chain of 1e6 particles) needs about 2 GB with an explicit method. Each
// element kind caps its own arrays (springs.h: kMaxSceneSprings). A scene
// file is also refused when it is larger than kMaxSceneFileBytes, nests
// deeper than kMaxSceneNesting or holds more than kMaxSceneJsonValues values:
// each is checked while reading, before the document is complete.
inline constexpr std::size_t kMaxSceneParticles = 1'000'000;
inline constexpr std::size_t kMaxSceneFileBytes = std::size_t{512} << 20;  // 512 MiB
inline constexpr std::size_t kMaxSceneNesting = 64;
inline constexpr std::size_t kMaxSceneJsonValues = 32'000'000;
// The JSON reader keeps every character between two strings or numbers for
// its messages: a long run of whitespace would cost its length in memory.
inline constexpr std::size_t kMaxJsonWhitespaceRun = std::size_t{1} << 20;  // 1 MiB

// What makes a text unfit for the JSON reader before it is parsed: a NUL
// byte (the reader would stop there and ignore the rest), or a run of
// whitespace over kMaxJsonWhitespaceRun. nullopt when none.
std::optional<std::string> json_text_problem(const std::string& text);

// A name or key as the user typed it, for a one-line message: control
// characters escaped (JSON style), at most 100 characters shown, then its
// length ("aaaa... (1048576 bytes)").
std::string printable(const std::string& text);

}  // namespace springlab
