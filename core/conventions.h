// hovs geometric conventions. Every header in core/ follows them; every other folder relies on them.
//
// Units
//   Lengths are metres, in files and in code. Angles are radians in code; reports may print degrees and say so.
//   Pixel pitch is metres per pixel (4.54 um = 4.54e-6).
//
// Frames
//   A transform is named target_from_source: cam_from_mirror maps a point given in the mirror frame into the
//   camera frame (p_cam = cam_from_mirror * p_mirror). world_from_rig, rig_from_unit, ... likewise.
//
//   Mirror frame: origin at the hyperboloid's outer focus F1 (the single effective viewpoint), z along the mirror
//   axis pointing from the camera towards the mirror, x and y such that for the aligned rig they coincide with
//   the camera's x (image columns) and y (image rows). It is right-handed. The ideal camera pinhole is the other
//   focus F2 = (0, 0, -2c).
//
//   Camera frame (pinhole): origin at the pinhole, x to the right (increasing u), y down (increasing v), z along
//   the optical axis, forwards. Right-handed.
//
//   Catadioptric models (exact hyperboloid, polynomial, unified) all return bearings in the mirror frame, so the
//   same virtual-camera or depth code works with any of them. Because a mirror image is a reflection, the
//   unified model written in this frame reads x / (xi*|X| - z) where Mei's paper reads x / (z + xi*|X|); the
//   conversion to OpenCV omnidir's frame is (x, y, -z) (see unified.h).
//
// Pixels
//   (u, v) = (column, row). The centre of the top-left pixel is (0, 0), as in OpenCV; the top-left corner of
//   the image is (-0.5, -0.5). An image of W x H pixels covers u in [-0.5, W - 0.5], v in [-0.5, H - 0.5].
//
// Bearings
//   Back-projections return unit 3-vectors, never (x, y, 1): catadioptric fields of view exceed 180 degrees.
//
// Scalars
//   Models are templates on the scalar type T so that ceres::Jet flows through them. Iterative inversions are
//   solved in double and lifted to T with one Newton step (implicit function theorem), which gives exact
//   first derivatives.
//
// Errors
//   Hot paths return bool / std::optional. Options and parameter structs have Check() which throws
//   hovs::Error. Broken invariants and bad files throw hovs::Error carrying what and where.
#pragma once
