#include "coupling/run.hpp"

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <memory>

#include "core/checkpoint.hpp"
#include "core/config.hpp"
#include "core/error.hpp"
#include "core/run_file.hpp"

namespace floesim {

RunSummary run_simulation(Simulation& sim, const RunOptions& options) {
  const Config& cfg = sim.scenario().config;
  const double t_end = options.until >= 0.0 ? options.until : cfg.run.t_end;
  const double interval = cfg.run.output_interval;
  const double checkpoint_interval = cfg.run.checkpoint_interval;
  const auto start = std::chrono::steady_clock::now();
  const parallel::Communicator& comm = sim.communicator();

  RunSummary summary;
  summary.output = options.output;
  summary.energy_first = sim.energies();
  summary.notes = sim.notes();
  // Records at t = 0, at every multiple of the interval and at the end.
  const auto expected_records = static_cast<std::size_t>(std::ceil(t_end / interval - 1e-9)) + 1;
  // One writer (rank 0): the other ranks hold the same state and have no file.
  std::unique_ptr<RunWriter> writer;
  const RunFileWriting file_writing = cfg.run.crash_safe_output ? RunFileWriting::crash_safe : RunFileWriting::in_place;
  comm.together([&] {
    if (!comm.writer()) return;
    writer = options.resume ? std::make_unique<RunWriter>(RunWriter::Resume{}, options.output, *options.resume,
                                                          resolved_toml(cfg), summary.energy_first.names, sim.sea_grid(),
                                                          file_writing)
                            : std::make_unique<RunWriter>(options.output, sim.floes(), resolved_toml(cfg),
                                                          summary.energy_first.names, sim.sea_grid(), expected_records,
                                                          file_writing);
    summary.xdmf = writer->xdmf_path();
  });

  // The writer's states at the last record, which the state kept at that
  // record (take_good, right after it) reuses: one gather a record.
  std::vector<FloeState> recorded;
  std::size_t recorded_steps = static_cast<std::size_t>(-1);  // steps() at that record
  auto record = [&] {
    PhaseTimer _(sim.profile(), Phase::record, comm);
    const Energies e = sim.energies();
    const std::span<const double> elevation = sim.sea_elevation();  // on every rank: it applies the sea's deferred kicks
    // The states from the floes' holders (collective), not the writer's own arrays.
    recorded = sim.writer_states();
    recorded_steps = sim.steps();
    if (writer) writer->record(sim.time(), sim.floes(), recorded, e.values, sim.lcp_counters(), elevation);
  };
  auto wall = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); };
  const double t_start = sim.time();
  const std::size_t steps_start = sim.steps();

  // Index of the next scheduled record: the first multiple of the interval
  // after the start (a simulation may come here already advanced).
  std::size_t next = 0;
  if (options.resume) {
    next = static_cast<std::size_t>(options.resume->next_record);
  } else {
    next = static_cast<std::size_t>(std::floor(sim.time() / interval)) + 1;
    if (static_cast<double>(next) * interval <= sim.time()) ++next;
  }
  // The state at the last record (a run error leaves the present state
  // half-stepped: that one is the checkpoint then), and the checkpoints.
  // save() is collective (a sea in slabs gathers its modes to rank 0); only
  // the writer keeps what it saved, the other ranks its step count. The old
  // state is let go before the new one is taken, so that the writer holds one
  // (on a large sea it is 64 B a cell); a failure while taking it then leaves
  // no state at a record, and the file keeps its last checkpoint.
  Checkpoint good;
  bool have_good = false;
  long long good_steps = -1;
  auto take_good = [&] {
    have_good = false;
    good = Checkpoint{};
    Checkpoint saved = recorded_steps == sim.steps() ? sim.save(std::move(recorded)) : sim.save();
    recorded_steps = static_cast<std::size_t>(-1);
    good_steps = saved.steps;
    if (writer) {
      good = std::move(saved);
      good.next_record = static_cast<long long>(next);
      writer->count_into(good);
    }
    have_good = true;
  };
  auto next_checkpoint_after = [&](double t) -> double {
    if (!(checkpoint_interval > 0.0)) return INFINITY;
    double k = std::floor(t / checkpoint_interval) + 1.0;
    if (k * checkpoint_interval <= t) k += 1.0;
    return k * checkpoint_interval;
  };
  double next_checkpoint = next_checkpoint_after(sim.time());
  std::size_t checkpoint_steps = static_cast<std::size_t>(-1);  // steps() at the last checkpoint
  auto checkpoint = [&] {
    PhaseTimer _(sim.profile(), Phase::record, comm);
    if (!(have_good && good_steps == static_cast<long long>(sim.steps()))) take_good();
    if (writer) writer->write_checkpoint(good);
    checkpoint_steps = sim.steps();
    summary.checkpoint_time = sim.time();
    next_checkpoint = next_checkpoint_after(sim.time());
  };

  summary.status = "complete";
  try {
    comm.together([&] {
      if (!options.resume) record();
      take_good();
    });
    while (sim.time() < t_end) {
      // Next record time; a record that would fall within 1e-9 s of the end merges with it.
      double t_record = std::min(static_cast<double>(next) * interval, t_end);
      if (t_end - t_record < 1e-9 * std::max(1.0, t_end)) t_record = t_end;
      bool stop = false;
      while (sim.time() < t_record && !stop) {
        // The ranks agree after each step, in one call: on a failure of any,
        // and on stopping.
        stop = comm.together_any([&] {
          sim.step(t_record);
          std::vector<CollisionEventRow> collisions = sim.take_collision_events();
          std::vector<FractureEventRow> events = sim.take_fracture_events();
          if (writer) {
            writer->note_floes(sim.floes());  // floes made by splits (numbers are never reused)
            writer->record_collisions(collisions);
            writer->record_fracture(events);
          }
          if (options.progress) options.progress({sim.time(), t_end, sim.steps(), wall(), t_start, steps_start});
        }, [&] { return options.should_stop && options.should_stop(); });
        if (!stop && sim.time() < t_record && sim.time() >= next_checkpoint) comm.together(checkpoint);
      }
      const bool on_schedule = sim.time() >= t_record;
      comm.together([&] {
        if (on_schedule) {
          record();
          ++next;
          take_good();
        }
        // An interruption saves the state before its record off the schedule,
        // which a restart drops (the run it continues has no such record).
        if (stop || (on_schedule && sim.time() >= next_checkpoint)) checkpoint();
        if (stop && !on_schedule) record();  // the last state of an interrupted run
      });
      if (stop) {
        summary.status = "interrupted";
        break;
      }
    }
    if (checkpoint_steps != sim.steps()) comm.together(checkpoint);
  } catch (const std::exception& e) {
    // Any failure marks the file failed with its reason (a RunError is the
    // expected kind; anything else is a bug, still recorded), with a
    // checkpoint at the last record unless writing is what failed. The
    // writer's own failures say what the file keeps; say it for the others.
    if (!writer) {  // not the writer rank: the same error, without the file's story
      if (dynamic_cast<const RunError*>(&e) == nullptr) throw;
      throw RunError(e.what());
    }
    const bool writing = writer->failed();
    const std::size_t kept = writer->records();
    std::string reason = std::string("failed: ") + e.what();
    bool checkpointed = false;
    if (have_good && !writing) {
      try {
        writer->write_checkpoint(good);
        summary.checkpoint_time = good.time;
        checkpointed = true;
      } catch (const std::exception& c) {
        reason += std::string(" (and ") + c.what() + ")";
      }
    }
    const std::string problem = writer->finish(reason);
    std::string message = e.what();
    if (!writing)
      message += "; the run file " + options.output + " keeps the " + std::to_string(kept) + " records written before";
    if (checkpointed) message += ", and a checkpoint at the last record (floesim run --restart)";
    if (!problem.empty()) message += "; " + problem;
    if (dynamic_cast<const RunError*>(&e) == nullptr) throw;
    throw RunError(message);
  }
  comm.together([&] {
    if (!writer) return;
    const std::string problem = writer->finish(
        summary.status == "complete" ? "complete" : "interrupted at t = " + std::to_string(sim.time()) + " s");
    if (!problem.empty()) throw RunError(writer->path() + ": the run ended but " + problem);
  });
  summary.steps = sim.steps();
  summary.records = writer ? writer->records() : 0;  // 0: this rank wrote no file
  summary.t_end = sim.time();
  summary.wall_seconds = wall();
  summary.energy_last = sim.energies();
  summary.profile = sim.profile();
  summary.warnings = sim.warnings();
  summary.collisions = sim.collision_stats();
  return summary;
}

}  // namespace floesim
