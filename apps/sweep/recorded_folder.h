// The folder of a resumable command (a sweep's, a reproduction's): a JSON
// record in it (sweep.json, reproduce.json) says what the folder was made
// for, so that the same command resumes there and another is refused. One
// home for creating such a folder and reading its record back; what counts
// as "the same" is the command's.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "core/json_io.h"

namespace uavsim::sim {

// DIR/NAME parsed, or nothing when it does not exist. A file that does not
// parse is a core::UsageError naming it ("FILE: unreadable (...); remove
// DIR or choose another --out").
std::optional<core::Json> ReadFolderRecord(const std::string& dir, const std::string& name);

// Creates DIR and DIR/SUB for each of `subfolders`, then writes `record` to
// DIR/NAME atomically (last: a folder without its record is not resumed).
// Throws std::runtime_error when a folder cannot be made.
void CreateRecordedFolder(const std::string& dir, const std::string& name, const core::Json& record,
                          const std::vector<std::string>& subfolders);

}  // namespace uavsim::sim
