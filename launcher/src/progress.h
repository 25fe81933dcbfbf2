#pragma once
// What `lockstep up` shows while a run goes and after it: a progress line (a bar on a
// terminal, a plain line every tenth of the run otherwise) and a summary with the
// figures of the run and what the services wrote. Plain functions over plain values,
// so they can be tested without processes.
#include <cstdint>
#include <string>
#include <vector>

namespace lockstep::launcher {

struct Progress {
  uint64_t frame = 0;        // last completed frame
  uint64_t total = 0;        // ticks the config asks for; 0 = until stopped
  double sim_time = 0;       // s
  double wall_s = 0;         // s since the run started ticking
  double tick_rate_hz = 0;   // recent window, from the coordinator
  std::string state;         // "running", "faulted", ...
};

// One line, at most `width` characters; with `bar` a [####....] bar of the done share.
std::string FormatProgress(const Progress& p, bool bar, size_t width);

// Whether a plain (non-terminal) progress line is due: once per tenth of the run, or
// every 500 frames when the run has no end. `last_reported` is the frame of the last one.
bool PlainLineDue(uint64_t frame, uint64_t total, uint64_t last_reported);

// Progress of long work that is not a run (`lockstep log` export, replay, diff): on a
// terminal a bar redrawn in place on stderr at most 10 times a second, otherwise a plain
// line every tenth; Done() ends it.
class WorkProgress {
 public:
  WorkProgress(std::string what, uint64_t total);
  void Update(uint64_t done, double sim_time);
  void Done();

 private:
  std::string what_;
  uint64_t total_;
  bool terminal_;
  double start_s_;
  double last_draw_s_ = -1;
  uint64_t last_plain_ = 0;
  bool drawn_ = false;
};

struct MemberFigures {
  std::string service;
  std::string kind;
  uint64_t last_frame = 0;
  double last_step_us = 0;
};

struct OutputGroup {
  std::string path;   // relative to the output folder
  uint64_t files = 0;
  uint64_t bytes = 0;
};

// Files under `dir` grouped by their folder (two levels deep at most), largest first.
std::vector<OutputGroup> ScanOutputs(const std::string& dir);

struct Summary {
  std::string name;       // config name
  std::string state;      // final run state
  uint64_t frames = 0;
  double sim_time = 0;    // s
  double wall_s = 0;      // s of ticking
  std::string failure;    // failed service and reason, if any
  std::vector<MemberFigures> members;
  std::string output_dir;
  std::vector<OutputGroup> outputs;
  std::vector<std::pair<std::string, std::string>> service_summaries;  // (file, text): each summary.txt found
};

std::string FormatSummary(const Summary& s);

}  // namespace lockstep::launcher
