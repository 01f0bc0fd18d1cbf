// --vtk with rigid bodies (experiments/io/vtk_bodies.h): each body's surface as
// triangles after the particles, its vertices at x = p + A X, where p and A
// are the run's final state as `run --json` reports it.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "models/bodies/bodies.h"
#include "models/scenes/builtin_scenes.h"
#include "models/core/scene.h"
#include "run_process.h"

namespace springlab::test_rigid_vtk {
namespace {

using namespace springlab::testing;

// The text of a DataArray in a frame: the first after the element `marker`
// ("<Points>"), or the one whose tag holds `marker` ("Name=\"types\"").
std::string array_after(const std::string& frame, const std::string& marker) {
  const auto at = frame.find(marker);
  EXPECT_NE(at, std::string::npos) << marker;
  if (at == std::string::npos) return "";
  const auto tag = marker[0] == '<' ? frame.find("<DataArray", at) : at;
  const auto start = frame.find('>', tag) + 1;
  return frame.substr(start, frame.find("</DataArray>", start) - start);
}

std::vector<double> numbers(const std::string& text) {
  std::istringstream in(text);
  std::vector<double> out;
  double x = 0.0;
  while (in >> x) out.push_back(x);
  return out;
}

TEST(RigidVtk, BodySurfaceIsDrawnAsTrianglesAtPPlusAX) {
  TempDir temp("rigid-vtk");
  fs::create_directories(temp.path() / "work");
  fs::create_directories(temp.path() / "io");
  const std::vector<std::string> args = {"run", "tumbling-box", "--integrator", "rk4", "--dt",
                                         "0.0005", "--t-end", "0.25", "--every", "100", "--vtk",
                                         "frames", "--json"};
  const ProcessResult r = run_springlab(args, temp.path() / "work", temp.path() / "io");
  ASSERT_TRUE(r.exited && r.status == 0) << describe(args, r);
  const nlohmann::json out = nlohmann::json::parse(r.out);
  ASSERT_EQ(out.at("status"), "completed");
  ASSERT_EQ(out.at("bodies").size(), 1u);
  const auto& body = out["bodies"][0];
  Eigen::Vector3d p;
  Eigen::Matrix3d A;
  for (int i = 0; i < 3; ++i) {
    p[i] = body["p"][i].get<double>();
    for (int j = 0; j < 3; ++j) A(i, j) = body["A"][i][j].get<double>();
  }
  // The box turned a quarter turn and more by t = 0.25 s: A is not I.
  ASSERT_GT((A - Eigen::Matrix3d::Identity()).norm(), 0.5);
  const RigidBody rb = rigid_body(make_builtin_scene("tumbling-box").get<Bodies>()[0]);
  ASSERT_EQ(rb.X.size(), 8u);
  ASSERT_EQ(rb.triangles.size(), 12u);
  const std::string frame = read_text(temp.path() / "work" / "frames" / "tumbling-box_000005.vtu");
  EXPECT_NE(frame.find("NumberOfPoints=\"8\" NumberOfCells=\"12\""), std::string::npos);
  const std::vector<double> points = numbers(array_after(frame, "<Points>"));
  ASSERT_EQ(points.size(), 24u);
  for (std::size_t k = 0; k < 8; ++k) {
    const Eigen::Vector3d x = p + A * rb.X[k];
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(points[3 * k + i], x[i], 1e-12) << k << " " << i;
  }
  std::string connectivity;
  for (const SurfaceTriangle& t : rb.triangles) {
    connectivity += std::to_string(t[0]) + ' ' + std::to_string(t[1]) + ' ' + std::to_string(t[2]) + ' ';
  }
  EXPECT_EQ(array_after(frame, "Name=\"connectivity\""), connectivity);
  EXPECT_EQ(array_after(frame, "Name=\"types\""), "5 5 5 5 5 5 5 5 5 5 5 5 ");
  EXPECT_EQ(numbers(array_after(frame, "Name=\"velocity\"")).size(), 24u);
}

}  // namespace
}  // namespace springlab::test_rigid_vtk
