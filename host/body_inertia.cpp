#include "host/body_inertia.h"

#include <Eigen/Eigenvalues>

namespace impact::host {

void body_inertia(const ShapeSet& shapes, ShapeId shape, float radius, float inv_mass, BodyRow* row) {
  const double mass = 1.0 / static_cast<double>(inv_mass);
  if (!shape.valid()) {
    const double ii = 1.0 / (0.4 * mass * static_cast<double>(radius) * radius);
    row->iix = row->iiy = row->iiz = static_cast<float>(ii);
    return;
  }
  MassProperties mp;
  if (!shapes.mass_properties(shape, 1.0f, &mp).ok() || !(mp.mass > 0.0)) {
    // No finite volume (validated bodies never get here): no rotation.
    row->iix = row->iiy = row->iiz = 0.0f;
    return;
  }
  const Eigen::Matrix3d inertia = mp.inertia * (mass / mp.mass);
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(inertia);
  Eigen::Matrix3d axes = es.eigenvectors();
  if (axes.determinant() < 0.0) axes.col(2) = -axes.col(2);  // a rotation, not a reflection
  const Eigen::Vector3d moments = es.eigenvalues();
  const Eigen::Quaterniond q(axes);
  row->pqx = static_cast<float>(q.x());
  row->pqy = static_cast<float>(q.y());
  row->pqz = static_cast<float>(q.z());
  row->pqw = static_cast<float>(q.w());
  auto inverse = [](double m) { return m > 0.0 ? static_cast<float>(1.0 / m) : 0.0f; };
  row->iix = inverse(moments.x());
  row->iiy = inverse(moments.y());
  row->iiz = inverse(moments.z());
  row->cx = static_cast<float>(mp.center_of_mass.x());
  row->cy = static_cast<float>(mp.center_of_mass.y());
  row->cz = static_cast<float>(mp.center_of_mass.z());
}

}  // namespace impact::host
