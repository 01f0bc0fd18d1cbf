#include "experiments/vtk_series.h"

#include <dirent.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>

#include "experiments/output_files.h"
#include "experiments/signals.h"

namespace springlab {
namespace {

// VTK's cell types (vtkCellType.h): a vertex, a line, a triangle, a tetrahedron.
constexpr int kVtkVertex = 1, kVtkLine = 3, kVtkTriangle = 5, kVtkTetra = 10;

int vtk_type(int size) {
  switch (size) {
    case 1: return kVtkVertex;
    case 2: return kVtkLine;
    case 3: return kVtkTriangle;
    default: return kVtkTetra;
  }
}

bool is_frame_of(const std::string& name, const std::string& stem) {
  if (name.size() != stem.size() + 11 || name.compare(0, stem.size() + 1, stem + "_") != 0) return false;
  for (std::size_t i = stem.size() + 1; i < stem.size() + 7; ++i) {
    if (name[i] < '0' || name[i] > '9') return false;
  }
  return name.compare(stem.size() + 7, 4, ".vtu") == 0;
}

}  // namespace

std::string vtk_stem(const std::string& scene_name) {
  std::string stem = scene_name.substr(0, 200);
  for (char& c : stem) {
    const bool keep = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                      c == '-' || c == '_' || c == '.';
    if (!keep) c = '_';
  }
  if (stem.empty() || stem[0] == '.') stem.insert(0, "scene");
  return stem;
}

void VtkSeries::fail(const std::string& what, int error) const {
  throw std::runtime_error(printable(dir_) + ": " + what + " (" + std::strerror(error) + ")");
}

VtkSeries::VtkSeries(const ElasticModel& model, const Scene& scene, std::string dir)
    : model_(model), dir_(std::move(dir)), stem_(vtk_stem(scene.name)) {
  if (dir_.empty()) throw std::runtime_error("--vtk: the folder name is empty");
  while (dir_.size() > 1 && dir_.back() == '/') dir_.pop_back();
  struct stat st {};
  if (::stat(dir_.c_str(), &st) == 0) {
    if (!S_ISDIR(st.st_mode)) throw std::runtime_error(printable(dir_) + ": is not a folder (--vtk DIR)");
    dir_existed_ = true;
  } else if (errno != ENOENT) {
    fail("cannot write", errno);
  }
  const std::string tag = ".springlab-tmp." + std::to_string(::getpid()) + "." + host_name() + ".XXXXXX";
  std::string name = dir_existed_ ? dir_ + "/" + tag : dir_ + tag;
  if (!create_temporary_series(name, stem_, &frames_)) fail("cannot write", errno);
  temp_dir_ = name;

  for (const Particle& p : scene.particles) fixed_.push_back(p.fixed ? 1 : 0);
  // The cells: every element, then a vertex for each particle none joins.
  std::vector<Cell> cells = scene_cells(scene);
  std::vector<bool> joined(scene.particles.size(), false);
  for (const Cell& c : cells) {
    for (int a = 0; a < c.size; ++a) joined[static_cast<std::size_t>(c.nodes[a])] = true;
  }
  for (std::size_t i = 0; i < joined.size(); ++i) {
    if (!joined[i]) cells.push_back({.size = 1, .nodes = {static_cast<int>(i), 0, 0, 0}});
  }
  std::string connectivity, offsets, types;
  long long offset = 0;
  for (const Cell& c : cells) {
    for (int a = 0; a < c.size; ++a) connectivity += std::to_string(c.nodes[a]) + ' ';
    offset += c.size;
    offsets += std::to_string(offset) + ' ';
    types += std::to_string(vtk_type(c.size)) + ' ';
  }
  cells_xml_ = "      <Cells>\n"
               "        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">" + connectivity +
               "</DataArray>\n"
               "        <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">" + offsets +
               "</DataArray>\n"
               "        <DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">" + types +
               "</DataArray>\n"
               "      </Cells>\n";
  cells_xml_.insert(0, "    <Piece NumberOfPoints=\"" + std::to_string(scene.particles.size()) +
                           "\" NumberOfCells=\"" + std::to_string(cells.size()) + "\">\n");
}

VtkSeries::~VtkSeries() {
  if (!published_) remove_temporary();
}

std::string VtkSeries::frame_name(int k) const {
  char digits[8];
  std::snprintf(digits, sizeof digits, "%06d", k);
  return stem_ + "_" + digits + ".vtu";
}

void VtkSeries::remove_temporary() {
  if (temp_dir_.empty()) return;
  const int frames = frames_.load();
  for (int k = 0; k <= frames; ++k) ::unlink((temp_dir_ + "/" + frame_name(k)).c_str());
  ::unlink((temp_dir_ + "/" + stem_ + ".pvd").c_str());
  ::rmdir(temp_dir_.c_str());
  unregister_temporary_series();
}

void VtkSeries::observe(double t, const Vector& x, const Vector& v) {
  const int k = frames_.load();
  if (k >= kMaxVtkFrames) {
    throw std::runtime_error(printable(dir_) + ": over " + std::to_string(kMaxVtkFrames) +
                             " frames: write every K-th step with --every");
  }
  // Points and velocities in 3-D (VTK's points have three coordinates; a
  // 2-D scene lies in z = 0).
  const Eigen::MatrixXd positions = model_.scene_positions(x);
  const Eigen::MatrixXd velocities = model_.scene_velocities(v);
  auto triples = [](const Eigen::MatrixXd& m) {
    std::string text;
    for (Eigen::Index i = 0; i < m.rows(); ++i) {
      for (Eigen::Index r = 0; r < 3; ++r) {
        text += r < m.cols() ? format_number(m(i, r)) : std::string("0");
        text += ' ';
      }
    }
    return text;
  };
  std::string fixed;
  for (unsigned char f : fixed_) fixed += f ? "1 " : "0 ";
  OutputFile file(temp_dir_ + "/" + frame_name(k));
  file.write("<?xml version=\"1.0\"?>\n"
             "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" "
             "header_type=\"UInt64\">\n"
             "  <UnstructuredGrid>\n"
             "    <FieldData>\n"
             "      <DataArray type=\"Float64\" Name=\"TimeValue\" NumberOfTuples=\"1\" format=\"ascii\">" +
             format_number(t) + "</DataArray>\n    </FieldData>\n");
  file.write(cells_xml_.substr(0, cells_xml_.find('\n') + 1));  // <Piece ...>
  file.write("      <PointData Vectors=\"velocity\" Scalars=\"fixed\">\n"
             "        <DataArray type=\"Float64\" Name=\"velocity\" NumberOfComponents=\"3\" format=\"ascii\">");
  file.write(triples(velocities));
  file.write("</DataArray>\n        <DataArray type=\"UInt8\" Name=\"fixed\" format=\"ascii\">" + fixed +
             "</DataArray>\n      </PointData>\n"
             "      <Points>\n        <DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">");
  file.write(triples(positions));
  file.write("</DataArray>\n      </Points>\n");
  file.write(cells_xml_.substr(cells_xml_.find('\n') + 1));
  file.write("    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n");
  file.publish();
  times_.push_back(t);
  frames_.store(k + 1);
}

void VtkSeries::publish() {
  if (published_) return;
  const std::string pvd_name = stem_ + ".pvd";
  {
    OutputFile pvd(temp_dir_ + "/" + pvd_name);
    std::string text =
        "<?xml version=\"1.0\"?>\n"
        "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n  <Collection>\n";
    for (std::size_t k = 0; k < times_.size(); ++k) {
      text += "    <DataSet timestep=\"" + format_number(times_[k]) + "\" group=\"\" part=\"0\" file=\"" +
              frame_name(static_cast<int>(k)) + "\"/>\n";
    }
    text += "  </Collection>\n</VTKFile>\n";
    pvd.write(text);
    pvd.publish();
  }
  const int frames = frames_.load();
  if (!dir_existed_ && ::rename(temp_dir_.c_str(), dir_.c_str()) == 0) {
    unregister_temporary_series();
    published_ = true;
    return;
  }
  if (!dir_existed_) {  // made by someone else meanwhile: move the files in
    struct stat st {};
    if (::stat(dir_.c_str(), &st) != 0) fail("cannot write", errno);
    if (!S_ISDIR(st.st_mode)) fail("cannot write", ENOTDIR);
  }
  for (int k = 0; k < frames; ++k) {
    const std::string name = frame_name(k);
    if (::rename((temp_dir_ + "/" + name).c_str(), (dir_ + "/" + name).c_str()) != 0) fail("cannot write", errno);
  }
  // Frames of an earlier, longer series of this stem would sit beside the
  // new ones: removed.
  if (DIR* d = ::opendir(dir_.c_str())) {
    while (const dirent* entry = ::readdir(d)) {
      const std::string name = entry->d_name;
      if (is_frame_of(name, stem_) && std::atoi(name.c_str() + stem_.size() + 1) >= frames) {
        ::unlink((dir_ + "/" + name).c_str());
      }
    }
    ::closedir(d);
  }
  if (::rename((temp_dir_ + "/" + pvd_name).c_str(), (dir_ + "/" + pvd_name).c_str()) != 0) {
    fail("cannot write", errno);
  }
  ::rmdir(temp_dir_.c_str());
  unregister_temporary_series();
  published_ = true;
}

}  // namespace springlab
