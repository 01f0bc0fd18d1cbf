#include "experiments/io/vtk_series.h"

#include "models/fluids/fluids.h"

#include <dirent.h>
#include <fcntl.h>
#include <signal.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <utility>

#include "experiments/io/output_files.h"
#include "experiments/io/signals.h"
#include "models/model/element_registry.h"

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

// The folder a publish moves the old series into, inside the temporary
// folder, until the new one is in place.
constexpr const char* kOldSeries = "old";

// Writes `text` to a new file `path` (0666 minus the umask); the errno of
// what failed, 0 when it worked.
int write_new_file(const std::string& path, const std::string& text) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC | O_NOCTTY, 0666);
  if (fd < 0) return errno;
  const char* data = text.data();
  std::size_t size = text.size();
  int error = 0;
  while (size > 0 && error == 0) {
    const ssize_t n = ::write(fd, data, size);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      error = errno;
      break;
    }
    data += n;
    size -= static_cast<std::size_t>(n);
  }
  if (::close(fd) != 0 && error == 0 && errno != EINTR) error = errno;
  return error;
}

// While alive, SIGINT, SIGTERM and SIGHUP wait (a publish's renames are
// not cut in half by Ctrl-C; one that came meanwhile is delivered after).
class SignalsHeld {
 public:
  SignalsHeld() {
    sigset_t held;
    sigemptyset(&held);
    for (int s : {SIGINT, SIGTERM, SIGHUP}) sigaddset(&held, s);
    ::pthread_sigmask(SIG_BLOCK, &held, &previous_);
  }
  ~SignalsHeld() { ::pthread_sigmask(SIG_SETMASK, &previous_, nullptr); }
  SignalsHeld(const SignalsHeld&) = delete;
  SignalsHeld& operator=(const SignalsHeld&) = delete;

 private:
  sigset_t previous_;
};

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

std::vector<std::string> VtkSeries::old_series() const {
  std::vector<std::string> names;
  DIR* d = ::opendir(dir_.c_str());
  if (d == nullptr) fail("cannot read", errno);
  while (const dirent* entry = ::readdir(d)) {
    const std::string name = entry->d_name;
    if (name == stem_ + ".pvd" || is_frame_of(name, stem_)) names.push_back(name);
  }
  ::closedir(d);
  std::sort(names.begin(), names.end());
  return names;
}

void VtkSeries::check_replaceable(const std::vector<std::string>& old) const {
  struct stat folder {};
  if (::stat(dir_.c_str(), &folder) != 0) fail("cannot write", errno);
  // A sticky folder (/tmp): only a file's owner (or the folder's) may
  // rename or remove it.
  const bool sticky = (folder.st_mode & S_ISVTX) != 0 && folder.st_uid != ::geteuid() && ::geteuid() != 0;
  for (const std::string& name : old) {
    const std::string path = dir_ + "/" + name;
    struct stat st {};
    if (::lstat(path.c_str(), &st) != 0) continue;  // gone meanwhile
    if (S_ISDIR(st.st_mode)) {
      throw std::runtime_error(printable(path) + ": is a folder, where the series' file goes (--vtk " +
                               printable(dir_) + "): remove or rename it");
    }
    if (sticky && st.st_uid != ::geteuid()) {
      throw std::runtime_error(printable(path) +
                               ": belongs to another user in a sticky folder, so it cannot be "
                               "replaced: choose another --vtk folder");
    }
  }
}

VtkSeries::VtkSeries(const Model& model, const Scene& scene, std::string dir)
    : model_(model), dir_(std::move(dir)), stem_(vtk_stem(scene.name)),
      bodies_(scene, model.particle_order().first_own(kBodyKind)) {
  if (dir_.empty()) throw std::runtime_error("--vtk: the folder name is empty");
  while (dir_.size() > 1 && dir_.back() == '/') dir_.pop_back();
  struct stat st {};
  if (::stat(dir_.c_str(), &st) == 0) {
    if (!S_ISDIR(st.st_mode)) throw std::runtime_error(printable(dir_) + ": is not a folder (--vtk DIR)");
    dir_existed_ = true;
  } else if (errno != ENOENT) {
    fail("cannot write", errno);
  }
  const std::string host = host_name();
  const std::string tag = ".springlab-tmp.";
  const std::string suffix = std::to_string(::getpid()) + "." + host + ".XXXXXX";
  std::string name;
  if (dir_existed_) {
    // Everything a publish needs, checked before the run: the folder may be
    // written, and no old file of the series is one it could not replace.
    if (::faccessat(AT_FDCWD, dir_.c_str(), W_OK | X_OK, AT_EACCESS) != 0) fail("cannot write", errno);
    check_replaceable(old_series());
    remove_stale_temporary_folders(dir_, tag);
    name = dir_ + "/" + tag + suffix;
  } else {
    const auto slash = dir_.rfind('/');
    const std::string parent = slash == std::string::npos ? "." : slash == 0 ? "/" : dir_.substr(0, slash);
    remove_stale_temporary_folders(parent, dir_.substr(slash == std::string::npos ? 0 : slash + 1) + tag);
    name = dir_ + tag + suffix;
  }
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
  bodies_.append_cells(static_cast<int>(scene.particles.size()), cells);
  bodies_.append_fixed(fixed_);
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
  const std::size_t points = scene.particles.size() + static_cast<std::size_t>(bodies_.points());
  cells_xml_.insert(0, "    <Piece NumberOfPoints=\"" + std::to_string(points) +
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
  ::rmdir((temp_dir_ + "/" + kOldSeries).c_str());
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
  Eigen::MatrixXd positions = model_.scene_positions(x);
  Eigen::MatrixXd velocities = model_.scene_velocities(v);
  if (bodies_.points() > 0) {  // the bodies' surface vertices after the particles
    Eigen::MatrixXd body_x, body_v;
    bodies_.states(x, v, body_x, body_v);
    const Eigen::Index n = positions.rows();
    positions.conservativeResize(n + body_x.rows(), 3);
    velocities.conservativeResize(n + body_v.rows(), 3);
    positions.bottomRows(body_x.rows()) = body_x;
    velocities.bottomRows(body_v.rows()) = body_v;
  }
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
  // A scene with fluids: each point's SPH density and pressure
  // (models/fluids/fluids.h; 0 for a point of no fluid).
  std::string fluid_data;
  if (const Fluids* fluids = model_.scene().find<Fluids>(); fluids != nullptr && !fluids->empty()) {
    const Eigen::Index points = positions.rows();
    std::vector<double> density(static_cast<std::size_t>(points), 0.0), pressure(density);
    const int dim = model_.dimension();
    std::vector<double> flat(static_cast<std::size_t>(model_.particle_count() * dim));
    for (int s = 0; s < model_.particle_count(); ++s) {
      for (int r = 0; r < dim; ++r) flat[static_cast<std::size_t>(s * dim + r)] = positions(s, r);
    }
    for (const Fluid& f : *fluids) {
      const FluidFields fields = fluid_fields(model_.scene(), f, flat.data());
      for (int a = 0; a < f.count; ++a) {
        density[static_cast<std::size_t>(f.first + a)] = fields.density[static_cast<std::size_t>(a)];
        pressure[static_cast<std::size_t>(f.first + a)] = fields.pressure[static_cast<std::size_t>(a)];
      }
    }
    auto list = [](const std::vector<double>& values) {
      std::string text;
      for (double value : values) text += format_number(value) + ' ';
      return text;
    };
    fluid_data = "        <DataArray type=\"Float64\" Name=\"density\" format=\"ascii\">" +
                 list(density) + "</DataArray>\n" +
                 "        <DataArray type=\"Float64\" Name=\"pressure\" format=\"ascii\">" +
                 list(pressure) + "</DataArray>\n";
  }
  // Straight into the temporary folder, which is ours and registered
  // (signals.h): no temporary of its own, and no listing of the folder per
  // frame (which made a series quadratic in its frames, issue 38.4).
  std::string text =
      "<?xml version=\"1.0\"?>\n"
      "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" "
      "header_type=\"UInt64\">\n"
      "  <UnstructuredGrid>\n"
      "    <FieldData>\n"
      "      <DataArray type=\"Float64\" Name=\"TimeValue\" NumberOfTuples=\"1\" format=\"ascii\">" +
      format_number(t) + "</DataArray>\n    </FieldData>\n";
  text += cells_xml_.substr(0, cells_xml_.find('\n') + 1);  // <Piece ...>
  text += "      <PointData Vectors=\"velocity\" Scalars=\"fixed\">\n"
          "        <DataArray type=\"Float64\" Name=\"velocity\" NumberOfComponents=\"3\" format=\"ascii\">";
  text += triples(velocities);
  text += "</DataArray>\n        <DataArray type=\"UInt8\" Name=\"fixed\" format=\"ascii\">" + fixed +
          "</DataArray>\n" + fluid_data + "      </PointData>\n"
          "      <Points>\n        <DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">";
  text += triples(positions);
  text += "</DataArray>\n      </Points>\n";
  text += cells_xml_.substr(cells_xml_.find('\n') + 1);
  text += "    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n";
  if (const int error = write_new_file(temp_dir_ + "/" + frame_name(k), text); error != 0) {
    fail("write failed", error);
  }
  times_.push_back(t);
  frames_.store(k + 1);
}

// Moves `names` from folder `from` to folder `to`; on a failure, moves back
// the ones it moved and returns the error (0: all moved).
namespace {
int move_all(const std::vector<std::string>& names, const std::string& from, const std::string& to,
             std::string& failed) {
  for (std::size_t k = 0; k < names.size(); ++k) {
    if (::rename((from + "/" + names[k]).c_str(), (to + "/" + names[k]).c_str()) != 0) {
      const int error = errno;
      failed = to + "/" + names[k];
      for (std::size_t back = k; back-- > 0;) {
        ::rename((to + "/" + names[back]).c_str(), (from + "/" + names[back]).c_str());
      }
      return error;
    }
  }
  return 0;
}
}  // namespace

void VtkSeries::publish() {
  if (published_) return;
  const std::string pvd_name = stem_ + ".pvd";
  std::string text =
      "<?xml version=\"1.0\"?>\n"
      "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n  <Collection>\n";
  for (std::size_t k = 0; k < times_.size(); ++k) {
    text += "    <DataSet timestep=\"" + format_number(times_[k]) + "\" group=\"\" part=\"0\" file=\"" +
            frame_name(static_cast<int>(k)) + "\"/>\n";
  }
  text += "  </Collection>\n</VTKFile>\n";
  if (const int error = write_new_file(temp_dir_ + "/" + pvd_name, text); error != 0) {
    fail("write failed", error);
  }
  const SignalsHeld held;  // from here to the end, or the failure that puts DIR back
  const int frames = frames_.load();
  if (!dir_existed_) {
    // The whole folder at once, with the bits a new folder gets (0777
    // minus the umask; it was 0700 while private).
    const mode_t mask = ::umask(0);
    ::umask(mask);
    if (::chmod(temp_dir_.c_str(), 0777 & ~mask) != 0) fail("cannot write", errno);
    if (::rename(temp_dir_.c_str(), dir_.c_str()) == 0) {
      unregister_temporary_series();
      published_ = true;
      return;
    }
    // Made by someone else meanwhile: the files are moved in, as below.
    if (errno != EEXIST && errno != ENOTEMPTY) fail("cannot write", errno);
    struct stat st {};
    if (::stat(dir_.c_str(), &st) != 0) fail("cannot write", errno);
    if (!S_ISDIR(st.st_mode)) fail("cannot write", ENOTDIR);
  }
  // DIR exists: its old series (frames and .pvd of this stem) is moved
  // aside into the temporary folder, the new one in, the .pvd last, and
  // only then the old one removed. A rename that fails puts back what was
  // moved, so DIR stays as it was (issue 38.3).
  std::vector<std::string> fresh;
  for (int k = 0; k < frames; ++k) fresh.push_back(frame_name(k));
  fresh.push_back(pvd_name);
  const std::vector<std::string> old = old_series();
  check_replaceable(old);
  const std::string aside = temp_dir_ + "/" + kOldSeries;
  if (::mkdir(aside.c_str(), 0700) != 0) fail("cannot write", errno);
  std::string failed;
  if (const int error = move_all(old, dir_, aside, failed); error != 0) {
    ::rmdir(aside.c_str());
    throw std::runtime_error(printable(dir_ + "/" + failed.substr(failed.rfind('/') + 1)) +
                             ": cannot be replaced (" + std::strerror(error) + "); " +
                             printable(dir_) + " is as it was");
  }
  if (const int error = move_all(fresh, temp_dir_, dir_, failed); error != 0) {
    std::string ignored;
    const bool restored = move_all(old, aside, dir_, ignored) == 0;
    ::rmdir(aside.c_str());
    throw std::runtime_error(printable(failed) + ": cannot write (" + std::strerror(error) + "); " +
                             printable(dir_) +
                             (restored ? " is as it was" : " lost its old series, kept in " + printable(aside)));
  }
  for (const std::string& name : old) ::unlink((aside + "/" + name).c_str());
  ::rmdir(aside.c_str());
  ::rmdir(temp_dir_.c_str());
  unregister_temporary_series();
  published_ = true;
}

}  // namespace springlab
