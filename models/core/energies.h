// Energies as named columns (docs/physics.md "Energies", docs/command-line.md "The command line"):
// the `--energy` CSV, the energy experiment's table and the settings JSON ("energy_columns") all
// take their columns from here, so an element kind that stores energy (element_kind.h) adds its
// column by registering it, and every writer reports it.
//
// The columns are, in this order: kinetic; the potentials every scene
// reports (spring, gravity); total (kinetic plus every potential); then the
// potentials reported only when the scene has their kind (elastic, contact).
// Within each group the order is the kind registry's.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace springlab {

class Scene;

// The column an element kind's potential energy is reported in.
struct EnergyColumn {
  std::string_view name;  // empty: the kind stores no energy (drag, wind, damping)
  // Reported by every scene, 0 when it has nothing of this kind
  // (docs/command-line.md "The command line": spring, gravity); otherwise only by scenes that have
  // elements of it.
  bool always = false;
  // Counts with the spring energy in docs/command-line.md "The command line"'s divergence rule and
  // in its energy scale E_s (spring; docs/physics.md "Finite elements", "Contact with planes":
  // elastic, contact); gravity does not.
  bool counts_with_spring = false;
  // A work column (docs/physics.md "Energies": "viscous-work"): the work
  // done against the kind's dissipative force since t = 0, a number of the
  // run's history, not of its state. It is not a potential and not in the
  // total; model.energies() leaves it 0 and the time series that report it
  // (--energy) accumulate it with Model::column_power.
  bool work = false;
  // For a kind without keys of its own: whether a scene has its elements
  // (the column is reported only then). nullptr: its keys say.
  bool (*present)(const Scene& scene) = nullptr;
};

// The columns of one model's (or one table's) energy report.
struct EnergyLayout {
  std::vector<std::string> columns;  // "kinetic", "spring", "gravity", "total", ...
  std::size_t kinetic = 0;
  std::size_t total = 0;
  std::vector<std::size_t> potentials;          // positions of the potential columns
  // The subset of docs/command-line.md "The command line"'s rule.
  std::vector<std::size_t> counts_with_spring;
  // The work columns (EnergyColumn::work), after the potentials.
  std::vector<std::size_t> works;
  // Position of `column`, or columns.size() when the layout has none.
  std::size_t find(std::string_view column) const;
};

// The energies of one state, one value per column of the layout.
class Energies {
 public:
  explicit Energies(std::shared_ptr<const EnergyLayout> layout);

  const std::vector<std::string>& columns() const { return layout_->columns; }
  // In the order of columns(); total() is filled in by finish().
  const std::vector<double>& values() const { return values_; }
  double kinetic() const { return values_[layout_->kinetic]; }
  double total() const { return values_[layout_->total]; }
  // Kinetic energy plus the magnitudes of the potentials that count with the
  // spring energy (so that none cancels another): what docs/command-line.md
  // "The command line"'s divergence rule compares with blowup x E_s.
  double kinetic_and_spring() const;
  // The value of a named column; throws std::out_of_range for a column the
  // layout does not have.
  double operator[](std::string_view column) const;

  // For the model: set the kinetic energy, add a potential to its column
  // (a position in columns()), then finish() sums the total as
  // kinetic + each potential in column order.
  void set_kinetic(double value) { values_[layout_->kinetic] = value; }
  void add(std::size_t column, double value) { values_[column] += value; }
  void clear();
  void finish();

 private:
  std::shared_ptr<const EnergyLayout> layout_;
  std::vector<double> values_;
};

}  // namespace springlab
