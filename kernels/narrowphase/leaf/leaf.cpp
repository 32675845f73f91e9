#include "kernels/narrowphase/leaf/leaf.h"

namespace impact::kernels {

const char* leaf_type_name(LeafType t) {
  switch (t) {
    case kLeafSphere: return "sphere";
    case kLeafCapsule: return "capsule";
    case kLeafBox: return "box";
    case kLeafConvex: return "convex";
    case kLeafCylinder: return "cylinder";
    case kLeafEllipsoid: return "ellipsoid";
    case kLeafTriangle: return "triangle";
    case kLeafHalfSpace: return "half-space";
    default: return "unknown";
  }
}

}  // namespace impact::kernels
