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
-- Elapsed time is os.clock(), the process's CPU time: right for the
-- single-threaded work it follows.

local type, error, setmetatable, pcall, require, pairs, tostring = type, error, setmetatable, pcall, require, pairs, tostring
local format, rep, floor = string.format, string.rep, math.floor
local clock = os and os.clock
local stderr = io and io.stderr

local _ENV = nil

local M = {}

local WIDTH = 24

-- Whether to draw: standard error is a terminal (false without the module's
-- helper) and femlod.quiet (the program's --quiet) is not set.
function M.enabled()
  local ok, femlod = pcall(require, "femlod")
  return ok and type(femlod) == "table" and femlod.quiet ~= true and type(femlod._isatty) == "function"
    and femlod._isatty(2) or false
end

local Bar = {}
Bar.__index = Bar

local function draw(b, done)
  local t = clock() - b.start
  local fill = floor(done * WIDTH + 0.5)
  local rate, eta = "?", "ETA ?"
  if done >= 0.01 and t > 0 then
    rate = format("%.0f", 100 * done / t)
    eta = format("ETA %.1f s", t * (1 - done) / done)
  end
  b.stream:write(format("\r\27[K%s [%s%s] %3d%%  %.1f s  %s %%/s  %s", b.label, rep("#", fill),
    rep(".", WIDTH - fill), floor(done * 100 + 0.5), t, rate, eta))
  b.stream:flush()
  b.drawn = true
end

local function update(b, done)
  if not b.on or type(done) ~= "number" then return nil end
  if done < 0 then done = 0 elseif done > 1 then done = 1 end
  local now = clock()
  if done < 1 and b.last and now - b.last < 0.1 then return nil end
  b.last = now
  draw(b, done)
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

-- bar{label = "work", force = false, stream = io.stderr}: force draws even
-- when standard error is not a terminal (tests); stream is where.
function M.bar(opts)
  if opts ~= nil and type(opts) ~= "table" then
    error(format("bad argument #1 to 'bar' (table expected, got %s)", type(opts)), 2)
  end
  opts = opts or {}
  for k in pairs(opts) do
    if k ~= "label" and k ~= "force" and k ~= "stream" then
      error(format("bad argument #1 to 'bar' (unknown option '%s'; valid: force, label, stream)", tostring(k)), 2)
    end
  end
  if opts.label ~= nil and type(opts.label) ~= "string" then
    error(format("bad argument #1 to 'bar' (label: string expected, got %s)", type(opts.label)), 2)
  end
  local stream = opts.stream or stderr
  local on = stream ~= nil and clock ~= nil and (opts.force == true or (opts.stream == nil and M.enabled()))
  local b = setmetatable({ label = opts.label or "work", stream = stream, on = on, start = clock and clock() or 0,
    drawn = false }, Bar)
  b.update = function(done) return update(b, done) end
  return b
end

return M
