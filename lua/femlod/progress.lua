-- femlod.progress: a progress bar with rate and ETA on standard error, drawn
-- only when standard error is a terminal (femlod._isatty) and the program
-- was not run with --quiet (femlod.quiet), for the progress option of
-- femlod.simplify, m:curvature, m:quality(reference, opts), h:rescale,
-- h:refine_curvature, h:refine_region, femlod.report and for recipes' own
-- loops.
--
--   local progress = require "femlod.progress"
--   local bar <close> = progress.bar { label = "simplify" }
--   local h <close> = mesh:simplify { target = 6000, progress = bar.update }
--
-- bar.update(done), done in [0, 1], is what simplify's progress option
-- calls; it returns nothing (so it never stops the work) and redraws at most
-- 10 times a second. bar:close() (or <close>) clears the line.
--
-- Time is the wall clock (femlod._clock): the core's work runs on several
-- threads, so the process's CPU time (os.clock) runs ahead of the time the
-- user waits. The bar is drawn as soon as it is made and moves (a marker
-- sliding along it, the elapsed time counting) while done stays at 0: the
-- set-up before the first collapse reports no fraction. The rate is measured
-- from the first call past 0, over windows of half a second, and smoothed;
-- the ETA shows only from a few percent on, when that rate means something.

local type, error, setmetatable, pcall, require, pairs, tostring = type, error, setmetatable, pcall, require, pairs, tostring
local format, rep, floor = string.format, string.rep, math.floor
local os_clock = os and os.clock
local stderr = io and io.stderr

local _ENV = nil

local M = {}

local WIDTH = 24
local REDRAW = 0.1   -- seconds between two draws
local WINDOW = 0.5   -- seconds of progress one rate sample spans
local SMOOTH = 0.3   -- weight of a new sample in the smoothed rate
local ETA_FROM = 0.03 -- fraction done before an ETA is shown

local function binding()
  local ok, femlod = pcall(require, "femlod")
  return ok and type(femlod) == "table" and femlod or nil
end

-- Whether to draw: standard error is a terminal (false without the module's
-- helper) and femlod.quiet (the program's --quiet) is not set.
function M.enabled()
  local femlod = binding()
  return femlod ~= nil and femlod.quiet ~= true and type(femlod._isatty) == "function"
    and femlod._isatty(2) or false
end

-- The clock the bars use: the binding's wall clock, else (plain Lua
-- without femlod) os.clock.
local function default_clock()
  local femlod = binding()
  if femlod and type(femlod._clock) == "function" then return femlod._clock end
  return os_clock
end

-- A rate in percent a second with two or three significant digits:
-- 123, 12.3, 1.23, 0.12.
function M.rate_text(r)
  if r >= 99.5 then return format("%.0f", r) end
  if r >= 9.95 then return format("%.1f", r) end
  if r >= 0.995 then return format("%.2f", r) end
  if r >= 0.001 then return format("%.2g", r) end
  return "<0.001"
end

-- A duration as people read it: 4.2 s, 35 s, 2 min 05 s, 1 h 02 min.
function M.time_text(t)
  if t < 9.95 then return format("%.1f s", t) end
  if t < 59.5 then return format("%.0f s", t) end
  local s = floor(t + 0.5)
  if s < 3600 then return format("%d min %02d s", s // 60, s % 60) end
  return format("%d h %02d min", s // 3600, s % 3600 // 60)
end

local Bar = {}
Bar.__index = Bar

-- The bar's cells: filled up to done, or, while done is 0, a marker that
-- moves one cell a draw so that the line visibly lives.
local function cells(b, done)
  if done > 0 then
    local fill = floor(done * WIDTH + 0.5)
    return rep("#", fill) .. rep(".", WIDTH - fill)
  end
  local at = b.spin % (2 * WIDTH - 6)
  if at > WIDTH - 3 then at = 2 * WIDTH - 6 - at end
  b.spin = b.spin + 1
  return rep(".", at) .. "===" .. rep(".", WIDTH - 3 - at)
end

-- The rate: a sample every WINDOW seconds of progress, smoothed.
local function measure(b, done, now)
  if done <= 0 then return end
  if not b.t0 then
    b.t0, b.d0 = now, done
    return
  end
  local dt = now - b.t0
  if dt >= WINDOW or (done >= 1 and dt > 0) then
    local sample = (done - b.d0) / dt
    b.rate = b.rate and b.rate + SMOOTH * (sample - b.rate) or sample
    b.t0, b.d0 = now, done
  end
end

local function draw(b, done, now)
  local t = now - b.start
  local tail
  if done <= 0 then
    tail = "starting"
  elseif b.rate and b.rate > 0 then
    tail = M.rate_text(100 * b.rate) .. " %/s"
    if done >= 1 then
      tail = tail .. "  done"
    elseif done >= ETA_FROM then
      tail = tail .. "  ETA " .. M.time_text((1 - done) / b.rate)
    else
      tail = tail .. "  ETA ?"
    end
  else
    tail = "? %/s  ETA ?"
  end
  b.stream:write(format("\r\27[K%s [%s] %3d%%  %s  %s", b.label, cells(b, done), floor(done * 100 + 0.5),
    M.time_text(t), tail))
  b.stream:flush()
  b.drawn = true
end

local function update(b, done)
  if not b.on or type(done) ~= "number" then return nil end
  if done < 0 then done = 0 elseif done > 1 then done = 1 end
  local now = b.clock()
  measure(b, done, now)
  if done < 1 and b.last and now - b.last < REDRAW then return nil end
  b.last = now
  draw(b, done, now)
  return nil
end

function Bar.close(b)
  if b.on and b.drawn then
    b.stream:write("\r\27[K")
    b.stream:flush()
  end
  b.drawn = false
  b.on = false
end
Bar.__close = Bar.close

local KEYS = { label = true, force = true, stream = true, clock = true }

-- bar{label = "work", force = false, stream = io.stderr, clock = nil}: force
-- draws even when standard error is not a terminal (tests); stream is where;
-- clock a function returning seconds (default the wall clock).
function M.bar(opts)
  if opts ~= nil and type(opts) ~= "table" then
    error(format("bad argument #1 to 'bar' (table expected, got %s)", type(opts)), 2)
  end
  opts = opts or {}
  for k in pairs(opts) do
    if not KEYS[k] then
      error(format("bad argument #1 to 'bar' (unknown option '%s'; valid: clock, force, label, stream)",
        tostring(k)), 2)
    end
  end
  if opts.label ~= nil and type(opts.label) ~= "string" then
    error(format("bad argument #1 to 'bar' (label: string expected, got %s)", type(opts.label)), 2)
  end
  if opts.clock ~= nil and type(opts.clock) ~= "function" then
    error(format("bad argument #1 to 'bar' (clock: function expected, got %s)", type(opts.clock)), 2)
  end
  local clock = opts.clock or default_clock()
  local stream = opts.stream or stderr
  local on = stream ~= nil and clock ~= nil and (opts.force == true or (opts.stream == nil and M.enabled()))
  local b = setmetatable({ label = opts.label or "work", stream = stream, on = on, clock = clock,
    start = clock and clock() or 0, drawn = false, spin = 0 }, Bar)
  b.update = function(done) return update(b, done) end
  if on then
    b.last = b.start
    draw(b, 0, b.start)
  end
  return b
end

return M
