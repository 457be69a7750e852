// kdmesh — sizing field (STUB: uniform max_size; the real implementation replaces this file).
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "sizing/sizing_field.h"

#include "core/error.h"

namespace kdmesh {

struct SizingField::Impl {
  SizingOptions options;
};

double SizingField::operator()(const double*) const { return impl_->options.max_size; }
double SizingField::max_size() const { return impl_->options.max_size; }
double SizingField::min_size() const { return impl_->options.min_size; }
const SizingOptions& SizingField::options() const { return impl_->options; }

SizingField build_sizing_field(const SurfaceMesh&, const SizingOptions& options) {
  if (!(options.max_size > 0)) throw UsageError("sizing: max_size must be > 0");
  auto impl = std::make_shared<SizingField::Impl>();
  impl->options = options;
  if (impl->options.min_size <= 0) impl->options.min_size = options.max_size / 1000;
  return SizingField(impl);
}

}  // namespace kdmesh
