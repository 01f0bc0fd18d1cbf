// --vtk DIR: the run's output frames for ParaView (docs/command-line.md, "ParaView").
//
// One VTK XML UnstructuredGrid file per output time, `DIR/<stem>_NNNNNN.vtu`
// (points with their velocity and a `fixed` flag; springs as lines,
// triangles and tetrahedra as cells; a particle no element joins as a
// vertex; then each rigid body's surface vertices as points, its triangles
// as cells: vtk_bodies.h), and `DIR/<stem>.pvd`, the series with each frame's time, which is
// what ParaView opens. <stem> is the scene's name with anything but letters,
// digits, '-', '_' and '.' made '_'.
//
// Written whole or not at all, like every output file (output_files.h): the
// frames go to a temporary folder (`DIR.springlab-tmp.<pid>.<host>.XXXXXX`
// beside DIR when DIR does not exist yet, `DIR/.springlab-tmp...` when it
// does), which publish() renames to DIR (mode 0777 minus the umask), or
// whose files it moves into DIR: the old series of the same stem (frames
// and .pvd) is first moved aside into the temporary folder, the new frames
// and then the .pvd moved in, and the old series removed last; a rename that
// fails puts everything back. What could make that fail (DIR not writable,
// a folder where the .pvd or a frame goes, another user's old file in a
// sticky folder) is refused before the run. A run that ends without
// publish(), by a signal, or by a failed publish leaves DIR as it was.
// Signals wait while publish() moves files. A temporary folder left by a
// killed run (kill -9) is removed by the next --vtk run beside it, once its
// process is gone (output_files.h).
#pragma once

#include <atomic>
#include <string>
#include <vector>

#include "experiments/driver/simulation.h"
#include "experiments/io/vtk_bodies.h"
#include "models/core/element_kind.h"

namespace springlab {

class VtkSeries final : public Observer {
 public:
  // Throws std::runtime_error naming DIR when it cannot be written.
  VtkSeries(const Model& model, const Scene& scene, std::string dir);
  ~VtkSeries() override;
  VtkSeries(const VtkSeries&) = delete;
  VtkSeries& operator=(const VtkSeries&) = delete;

  void observe(double t, const Vector& x, const Vector& v) override;
  // Writes the .pvd and puts the series in DIR.
  void publish();
  const std::string& dir() const { return dir_; }

 private:
  std::string frame_name(int k) const;
  // The files of this stem's series in DIR (frames and .pvd), sorted.
  std::vector<std::string> old_series() const;
  // Throws, naming the file, when one of `old` could not be replaced: a
  // folder in its place, or another user's file in a sticky folder.
  void check_replaceable(const std::vector<std::string>& old) const;
  void remove_temporary();
  [[noreturn]] void fail(const std::string& what, int error) const;

  const Model& model_;
  std::string dir_, temp_dir_, stem_;
  bool dir_existed_ = false, published_ = false;
  std::vector<unsigned char> fixed_;
  VtkBodies bodies_;  // rigid bodies' surfaces: points after the particles'
  std::string cells_xml_;  // the <Cells> block: the same in every frame
  std::vector<double> times_;
  std::atomic<int> frames_{0};
};

// Frames are numbered with six digits: at most this many per series (the
// command line refuses more before the run starts).
inline constexpr int kMaxVtkFrames = 1'000'000;

// The scene name as a file-name stem (see above); "scene" when empty.
std::string vtk_stem(const std::string& scene_name);

}  // namespace springlab
