#pragma once
// A spatial robot's attachment points measured from camera images and registered into its frames
// (Mauze et al. 2021, Section 4, in 3-D; the planar pipeline's steps 3-4, pcr/vision/measure.hpp):
//
// 1. Points. Each hole A_i on the base and each attachment point B_i on the platform has a tag
//    next to it and is known in that tag's frame (the attachment layout file); one image of the
//    base measures the A_i, one of the platform (at any pose) the B_i, each in the camera frame S
//    with its covariance (measure_tag_points: the point from its own tag's pose).
// 2. Frames. W is the least-squares rigid registration of the measured A_i onto the design's A_i
//    (pcr::fit_rigid_motion), P the one of the measured B_i onto the design's B_i (the usual
//    metrology best fit, as the planar step 4), so the results are in the design's frames and
//    directly comparable with it.
// 3. Half-widths: k sigma of the covariance propagated linearly through the registration (k =
//    MeasureOptions::coverage_factor) plus the worst case of the layout's offset tolerances
//    propagated alike (measured_half_widths, the planar rule).
//
// Everything else (the rods' frames, lengths, moduli, the extrinsics and their half-widths) is
// kept from the design: a tag next to a point measures the point, not the rod's direction there.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "pcr/spatial/robot_io.hpp"
#include "pcr/vision/image.hpp"
#include "pcr/vision/measure.hpp"
#include "pcr/vision/tag_board.hpp"

namespace pcr::vision {

/// Where each rod's points are marked: the tag next to its hole A_i and the tag next to its
/// attachment point B_i, with the point in the tag's frame (TagPoint::offset) and that offset's
/// tolerance (TagPoint::offset_uncertainty).
struct AttachmentLayout {
  std::string source;                 ///< the file, for messages
  std::vector<TagPoint> holes;        ///< A_1..A_n, rod order (names "A1".."An")
  std::vector<TagPoint> attachments;  ///< B_1..B_n (names "B1".."Bn")
  int num_rods() const { return static_cast<int>(holes.size()); }
};

/// The attachment layout file (JSON, SI units; docs/vision.md, "The attachment layout file"):
///   {
///     "format": "pcr-attachment-points", "version": 1,   // both optional
///     "family": "tag36h11", "tag_size": 0.04,            // defaults for the tags (optional)
///     "rods": [                                          // one per rod, in the robot's order
///       { "A": {"id": 20, "family": ..., "tag_size": ..., "offset": [x, y, z],
///               "offset_uncertainty": [hx, hy, hz], "comment": ...},   // the hole A_i
///         "B": {...},                                                  // the point B_i
///         "comment": ... } ]
///   }
/// `offset`: the point in its tag's frame (pcr/vision/tags.hpp: centre, x to the bitmap's right,
/// y to its top, z out of its face), m; `offset_uncertainty` (optional, 0): its half-widths along
/// the tag's axes, m. Every tag (A and B) has its own family and id. Every error names `source`,
/// the field and the value: an unknown field, a missing one, an unknown family, an id the family
/// lacks, a size outside (0, 10) m, a family and id given twice.
AttachmentLayout parse_attachment_layout(const std::string& json_text, const std::string& source,
                                         const std::string& family = kDefaultTagFamily);
AttachmentLayout load_attachment_layout(const std::string& path,
                                        const std::string& family = kDefaultTagFamily);

/// One set of points registered onto its design: a frame F (W or P) and the points in it.
struct PointRegistration {
  SpatialPose<double> camera_T_frame;        ///< ^S T_F, from the fit
  std::vector<Eigen::Vector3d> points;       ///< in F (m)
  std::vector<Eigen::Vector3d> half_widths;  ///< along F's axes (m)
  Eigen::MatrixXd covariance;                ///< 3n x 3n, of the points in F, from the image (m^2)
  double rms{0};                             ///< of |point - design point| (m)
};

/// Registers the points `measured` (in S, of `points`, in order) onto `design` (in F): the
/// least-squares rigid fit F <- S, the points mapped by it, their covariance propagated linearly
/// through the map and the fit together, half-widths by measured_half_widths with the offsets'
/// tolerances. `what` names the set in messages ("the base's holes A_i"); InputError when there
/// are fewer than 3 points or the design's are collinear (the frame is then undetermined).
PointRegistration register_points(const std::vector<TagPoint>& points,
                                  const std::vector<TagPointMeasurement>& measured,
                                  const std::vector<Eigen::Vector3d>& design,
                                  double coverage_factor, const std::string& what);

struct AttachmentMeasurement {
  std::vector<TagPointMeasurement> holes;        ///< the A_i in the base image's camera frame
  std::vector<TagPointMeasurement> attachments;  ///< the B_i in the platform image's
  PointRegistration A;                           ///< the A_i in W
  PointRegistration B;                           ///< the B_i in P
};

/// The A_i in `base_image` and the B_i in `platform_image` (measure_tag_points), registered onto
/// `design`'s. Throws InputError naming the layout file and the design for a rod count that
/// differs, naming the image and the point for a tag not seen (as measure_tag_points).
AttachmentMeasurement measure_attachment_points(
    const GrayImage& base_image, const std::string& base_source, const GrayImage& platform_image,
    const std::string& platform_source, const AttachmentLayout& layout, const CameraModel& camera,
    const SpatialRobotDescription& design, const MeasureOptions& options = {});

/// `design` with the measured A_i and B_i and an uncertainty whose rods' A and B half-widths are
/// the measured ones (its other fields from the design's uncertainty, or the reference robot's,
/// continuum_stewart_gough_uncertainty, when the design has none: as the planar
/// measured_description).
SpatialRobotDescription measured_spatial_description(const SpatialRobotDescription& design,
                                                     const AttachmentMeasurement& measurement);

}  // namespace pcr::vision
