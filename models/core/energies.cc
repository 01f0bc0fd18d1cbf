#include "models/core/energies.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace springlab {

std::size_t EnergyLayout::find(std::string_view column) const {
  const auto it = std::find(columns.begin(), columns.end(), column);
  return static_cast<std::size_t>(it - columns.begin());
}

Energies::Energies(std::shared_ptr<const EnergyLayout> layout)
    : layout_(std::move(layout)), values_(layout_->columns.size(), 0.0) {}

double Energies::kinetic_and_spring() const {
  // Each potential's magnitude: a negative one (an energy below its rest
  // state's) must not cancel a kinetic energy that blows up.
  double sum = kinetic();
  for (std::size_t c : layout_->counts_with_spring) sum += std::abs(values_[c]);
  return sum;
}

double Energies::operator[](std::string_view column) const {
  const std::size_t c = layout_->find(column);
  if (c == values_.size()) {
    throw std::out_of_range("energies: no column '" + std::string(column) + "'");
  }
  return values_[c];
}

void Energies::clear() { std::fill(values_.begin(), values_.end(), 0.0); }

void Energies::finish() {
  double sum = kinetic();
  for (std::size_t c : layout_->potentials) sum += values_[c];
  values_[layout_->total] = sum;
}

}  // namespace springlab
