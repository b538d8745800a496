// Tags of an AprilTag board found from their found neighbours.
//
// libapriltag finds a tag by its own outline: the threshold image is cut into
// dark and light regions, and a tag is a dark region whose boundary with the
// light region around it is a quad. On Kalibr's AprilGrid (SPEC 7.2) a black
// square touches each tag at each corner; with the blur of a real lens and
// the threshold's window, squares and tags merge into one dark region, the
// light around a tag is cut into four strips, and no quad of the tag's own
// is left: libapriltag misses the tag (on yac_d435i_aprilgrid it found 899
// of the 1,007 tags yac's detector listed, some photos only 18 of 34).
// Dilating the light regions to separate them costs more tags than it wins.
//
// But a board's layout says where its other tags are once some are found.
// GrowBoardTags, per AprilTag board, after libapriltag:
//  1. seeds: the board's tags that libapriltag found once and that were
//     refined (TagDetector::Refine). A tag found twice (two printed copies)
//     seeds nothing.
//  2. predicts each missing tag next to found ones: the homography from
//     board to image that the corners of its found neighbours fit (those in
//     the 3 x 3 cells around it; with fewer than two of them, those in the
//     5 x 5 cells) maps its quad into the image; where that does not lead
//     to the tag, each corner from the homographies of the found tags that
//     share that corner's junction. Over a few tags a homography follows the
//     lens's distortion to about a bit on TUM VI's fisheye views (measured:
//     0.5-1 bit typical, 2 bits and more at the image's edge).
//  3. snaps each predicted corner to the image's corner there
//     (cv::cornerSubPix in a window of about a bit, as Kalibr does): on an
//     AprilGrid the tag's corner and the square's meet in a saddle point.
//     A snap that moves a corner by a bit or more is not taken.
//  4. reads the tag's code through the homography of its four corners, at
//     every bit's centre: the black border must read black and the quiet
//     zone around it white (at most `max_frame_misses` of them wrong,
//     the corner bits that the AprilGrid's squares cover left out), and the
//     data bits must be the code of the id the board puts there, turned as
//     the board says, to within `max_hamming` bits. tag36h11's codes are 11
//     bits apart in any turn: a pattern within 2 bits of the expected code
//     is 9 or more from every other.
//  5. refines the corners as libapriltag's are (edges or pattern,
//     TagDetector::Refine) and keeps the tag only when that holds.
// A kept tag is a neighbour for the tags around it, which are tried (again)
// with it; a tag is tried again only when its found neighbours have
// changed, so the search ends, at most 24 tries per tag.
//
// What is kept is verified by the tag's own pixels: its bits read as the
// expected code and its own edges or pattern fitted its corners. Where the
// neighbours say a tag should be only tells where to look: a tag hidden,
// smudged, out of the photo or somewhere else is not found, and nothing is
// ever placed where a tag is not seen.
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "detect/detector.h"
#include "libcalib/model/targets.h"

namespace rtscalib::detect {

struct GrowthOptions {
  int max_hamming = 2;  // data bits that may read wrong (step 4)
  // Border and quiet-zone bits that may read wrong: a tenth of tag36h11's
  // 104 (2-bit border) or 60 (1-bit) frame bits. A first look before the
  // refinement may miss twice as many, and twice max_hamming (step 4).
  double max_frame_miss_fraction = 0.1;
  // Least ink-paper contrast of a tag read [grey levels] (the edge
  // refinement needs 10).
  double min_contrast = 10;

  std::string Check() const;  // empty when valid
};

// Appends to `detections` the tags of `board` (an AprilTag board) that the
// growth above finds, each with refinement set (kEdges or kPattern),
// `from_neighbours` true, `apriltag_corners` the snapped prediction it
// started from, and `hamming` its data bits read wrong. Detections of the
// board's tags that were not refined (libapriltag found them, the refinement
// did not hold) are removed when the growth finds the same tag. `detector`
// must detect the board's family with its border_bits (it refines).
void GrowBoardTags(const cv::Mat& gray, const TagBoard& board, TagDetector* detector,
                   std::vector<TagDetection>* detections, const GrowthOptions& options = {});

}  // namespace rtscalib::detect
