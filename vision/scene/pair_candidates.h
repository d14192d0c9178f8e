#pragma once

#include <vector>

#include "vision/scene/edge_segments.h"
#include "vision/scene/scene.h"

// Candidate pairs of one channel, from its edge segments at the detection scale, before any is
// followed along the full-resolution image (scene.cc's ChoosePair).
namespace clogscope::vision {

// Scores pairs of long segments as strand silhouettes: every parallel, overlapping pair seeds two
// lines, whose support is then counted over all edge points. Best first, at most 40. A strand's
// seed may close downward as a swell below the nozzle does, where it runs parallel below.
std::vector<PairCandidate> PairSegments(const Detection& d, const std::vector<EdgeSegment>& edges,
                                        double noise_full, int roi_width, const SceneOptions& o);

// Rules out `inner` as lying inside `outer`, a wider pair: the object.
void JudgeInsideWider(const PairCandidate& outer, PairCandidate* inner);

// Marks pairs lying inside a comparable outer pair along half their stretch or more (a highlight
// stripe, a clear strand's internal lines): the outer silhouette is the object.
void SuppressNested(MeasureTarget target, std::vector<PairCandidate>* cands);

// Whether a pair's inside is one object: a pair made of the outer edges of two strands side by
// side holds the background between them. Samples the inside at the detection scale and counts
// how much of it sits at the background's level (within a quarter of the step), and whether that
// makes a run clear of both rims (a gap). A transparent strand on a backlight is a lens: its core
// shows the backlight too, but as one band centred between two dark rims of equal width, and it
// is one object.
bool InsideIsOneObject(const Detection& d, const PairCandidate& c);

}  // namespace clogscope::vision
