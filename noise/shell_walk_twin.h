/// @file shell_walk_twin.h
/// @brief shaders/spot_tet_walk.h compiled for the CPU: the class body of the walk's twin,
/// included by noise/shell.cpp once inside spot::shared::f32 (float: the GPU's twin) and once
/// inside spot::shared::f64 (double), as shaders/spot_shared.hpp instantiates spot_shared.h.
///
/// No include guard on purpose; the includer's namespace gives `real`, `rvec3` and the rest.

/// The shared walk functions as member functions, reading the planes of the twin's arrays.
class TetWalkTwin {
public:
    explicit TetWalkTwin(const rvec4* planes) : m_planes(planes) {}
    /// Face f's plane of tetrahedron `tet`, as the walk reads it.
    rvec4 plane(uint tet, uint f) const { return spotWalkPlane(tet, f); }

private:
    const rvec4* m_planes; ///< 4 per tetrahedron, face f of tetrahedron t at 4 t + f
    rvec4 spotWalkPlane(uint tet, uint f) const { return m_planes[4u * tet + f]; }

public:
#include "shaders/spot_member_begin.h"
#include "shaders/spot_tet_walk.h"
#include "shaders/spot_member_end.h"
};
