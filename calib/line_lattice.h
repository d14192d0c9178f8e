#pragma once

#include <string>
#include <vector>

#include "calib/pixel_scale.h"

namespace clogscope::calib {

// A mark found across a stage micrometer image: a candidate line, which may be a tick of any
// length, a stroke of a printed numeral or dust.
struct LineMark {
  double position_px = 0;  // across the lines
  double sigma_px = 0;
  double length_px = 0;  // along the lines: of two marks in one slot, the longer is the line
};

struct LatticeOptions {
  double tolerance_spacings = 0.15;  // farther than this from its slot: off the lattice
  int min_lines = 5;                 // fewer lines on the lattice: refused
  // Marks shorter than this fraction of the upper quartile of the marks' lengths (a short tick's)
  // are no lines (0: keep all).
  double min_length_fraction = 0.5;
  // Another lattice (another spacing, or a multiple of this one) that takes this fraction of the
  // slots this one takes fits about as well: refused as ambiguous.
  double ambiguity_ratio = 0.75;
  // The marks left out off the lattice fill at least this fraction of the slots of a lattice of
  // their own, with min_lines lines or more and at least second_lattice_lines times as many as
  // this one: two spacings, refused. (Numerals and dust fall on a sparse lattice by chance.)
  double second_lattice_fill = 0.6;
  double second_lattice_lines = 0.15;
  bool Validate(std::string* why) const;
};

enum class LatticeStatus {
  kOk,
  kTooFewMarks,      // fewer marks than min_lines, or no spacing between them
  kTooFewOnLattice,  // fewer than min_lines marks on the best lattice
  kAmbiguous,        // two lattices fit about equally well
  kTwoSpacings,      // the marks left out form a lattice of their own
};
const char* LatticeStatusName(LatticeStatus status);

struct LatticeIndexing {
  LatticeStatus status = LatticeStatus::kTooFewMarks;
  std::string reason;   // when not ok
  double pitch_px = 0;  // the lattice's spacing
  double slot0_px = 0;  // position of slot 0 (the first line's)
  // The lines on the lattice, indexed from 0, by position: a mark, or pieces of one line (dust
  // splits a line) combined by their σ.
  std::vector<LineObservation> lines;
  std::vector<std::vector<int>> line_marks;  // for each line, the marks it came from
  int marks = 0;
  int off_lattice = 0;  // marks farther than the tolerance from every slot
  int shared_slot = 0;  // marks in a slot that holds a longer line
  int too_short = 0;    // marks far shorter than most, not tried on the lattice
  bool ok() const { return status == LatticeStatus::kOk; }
  int left_out() const { return off_lattice + shared_slot + too_short; }
  // "N of M marks left out: off the lattice", or how many for each reason when there are several.
  std::string LeftOutSummary() const;
};

// Fits the lattice (spacing and phase) that most marks sit on and numbers the marks on it. The
// spacing starts from the periodogram of the positions around their median nearest-neighbour
// spacing; every mark takes its nearest slot, those within the tolerance are fitted with a
// reweighted (Huber) line index → position, and the two steps repeat until the set is stable.
// Missing slots are fine; marks in one slot at one position are pieces of one line. Marks far
// shorter than most (dust, a numeral's stroke), marks off the lattice (numerals, dust between the
// lines) and marks beside a longer line in its slot are left out and counted. Refused (a status and
// a reason, never a lattice) when fewer than min_lines marks sit on it, when another spacing or a
// multiple of this one fits about as well, or when the marks left out form a lattice of their own
// (two spacings mixed). Throws std::invalid_argument for invalid options, a negative image number
// or a non-finite position.
LatticeIndexing IndexLinesOnLattice(const std::vector<LineMark>& marks, int image,
                                    const LatticeOptions& options = {});

}  // namespace clogscope::calib
