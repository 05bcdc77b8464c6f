#pragma once

// The index's GEOR section (format/index_sections.h) and the geo library's type.

#include "format/index_sections.h"
#include "geo/georeference.h"

namespace cwloc {

Georeference GeoreferenceOfSection(const IndexGeoreference& section);

// The camera centre of a model image (IMGS), in model coordinates.
Eigen::Vector3d CameraCenterOf(const IndexImage& image);

// The fit statistics and source are left for the caller.
IndexGeoreference SectionOfGeoreference(const Georeference& georeference);

}  // namespace cwloc
