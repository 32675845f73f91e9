#include "kernels/narrowphase/general/lane_contact.h"

namespace impact::kernels::cvx {

void write_lane(const ManifoldSoA& out, uint32_t k, const LaneContact& c, V3 origin) {
  out.count[k] = static_cast<uint8_t>(c.count);
  if (c.count == 0) return;
  out.n[0][k] = c.n.x;
  out.n[1][k] = c.n.y;
  out.n[2][k] = c.n.z;
  out.depth[k] = c.depth;
  for (uint32_t i = 0; i < c.count; ++i) {
    out.point[i][0][k] = c.point[i].x + origin.x;
    out.point[i][1][k] = c.point[i].y + origin.y;
    out.point[i][2][k] = c.point[i].z + origin.z;
    out.pdepth[i][k] = c.pdepth[i];
  }
}

}  // namespace impact::kernels::cvx
