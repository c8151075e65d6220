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

/// Bytes from a size as users write it: a number with an optional K, M, G or T suffix (powers of
/// 1024, e.g. "512M", "1.5G"; no suffix = bytes), "0" for no limit. Throws
/// CLI::ValidationError naming `option` for anything else.
std::size_t parse_byte_size(const std::string& text, const std::string& option);

/// Validator for options parsed with parse_byte_size().
CLI::Validator byte_size();

/// The --max-memory default: 80 % of the machine's physical memory (0 when it cannot be read).
std::size_t default_memory_limit();

}  // namespace meshflow::cli
