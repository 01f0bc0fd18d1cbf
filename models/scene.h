// The scene: what a scene file (SPEC §3) or a built-in scene (SPEC §4)
// describes, before any physics is assembled from it. Plain data; the model
// (mass_spring_model.h) turns it into forces and a state.
#pragma once

#include <Eigen/Core>
#include <cstddef>
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
};

struct Spring {
  int i = 0;
  int j = 0;
  double k = 0.0;
  double rest = 0.0;     // resolved: the initial distance when the file omits it
  double damping = 0.0;  // c in F_i = -c ((v_i - v_j).d) d
};

// w(t) = w0 (1 + gust sin(2 pi f t)); F_i = coefficient (w(t) - v_i)
struct Wind {
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();
  double coefficient = 0.0;
  double gust = 0.0;
  double frequency = 0.0;
};

struct Scene {
  std::string name;
  int dimension = 2;
  Eigen::Vector3d gravity = Eigen::Vector3d::Zero();
  double drag = 0.0;
  std::optional<Wind> wind;
  std::vector<Particle> particles;
  std::vector<Spring> springs;
};

// Resource caps (README, "Reliability"): a scene larger than this is refused
// before it is built, so a typo like n=100000 is a message, not an
// out-of-memory kill. The largest scene they allow (a 578 x 578 cloth, or a chain of
// 1e6 particles) needs about 2 GB with an explicit method. A scene
// file is also refused when it is larger than kMaxSceneFileBytes, nests deeper
// than kMaxSceneNesting or holds more than kMaxSceneJsonValues values: each is
// checked while reading, before the document is complete.
inline constexpr std::size_t kMaxSceneParticles = 1'000'000;
inline constexpr std::size_t kMaxSceneSprings = 2'000'000;
inline constexpr std::size_t kMaxSceneFileBytes = std::size_t{512} << 20;  // 512 MiB
inline constexpr std::size_t kMaxSceneNesting = 64;
inline constexpr std::size_t kMaxSceneJsonValues = 32'000'000;
// The JSON reader keeps every character between two strings or numbers for
// its messages: a long run of whitespace would cost its length in memory.
inline constexpr std::size_t kMaxJsonWhitespaceRun = std::size_t{1} << 20;  // 1 MiB

// Parses and validates a scene (SPEC §3). `source` names the file in messages.
// Throws SceneError on any violation; never returns a half-valid scene.
Scene parse_scene(const std::string& json_text, const std::string& source);
// `source` names the file in messages (default: the path). A FIFO or a
// pipe (/dev/stdin) is read like a file, within the same size cap.
Scene load_scene_file(const std::string& path, const std::string& source = "");

// The scene as a scene file (round-trips through parse_scene).
std::string scene_to_json(const Scene& scene);

// What makes a text unfit for the JSON reader before it is parsed: a NUL
// byte (the reader would stop there and ignore the rest), or a run of
// whitespace over kMaxJsonWhitespaceRun. nullopt when none.
std::optional<std::string> json_text_problem(const std::string& text);

// A name or key as the user typed it, for a one-line message: control
// characters escaped (JSON style), at most 100 characters shown, then its
// length ("aaaa... (1048576 bytes)").
std::string printable(const std::string& text);

// Runs every SPEC §3 check on an already-built scene (used for built-ins too).
void validate_scene(const Scene& scene, const std::string& source);

}  // namespace springlab
