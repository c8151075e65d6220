#pragma once
// Validators for the command line's numbers. CLI11's Range / PositiveNumber let NaN through
// (every comparison with it is false), accept "-1" for unsigned options (strtoull wraps it) and
// print a double's full range in their messages; these reject all three with a short message.

#include <CLI/CLI.hpp>

namespace meshflow::cli {

/// A finite number in [low, high] ((low, high] when `low_open`): "nan", "inf", "-1" for a
/// bound of 0 and words are usage errors ("--voxel: expected a number in [0, 1000], got 'nan'").
/// For integer options give whole bounds; CLI11 then also refuses fractions when it converts.
CLI::Validator number_in(double low, double high, bool low_open = false);

}  // namespace meshflow::cli
