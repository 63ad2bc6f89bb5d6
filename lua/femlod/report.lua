-- femlod.report: quality tables (mesh:quality()) as text.
--
--   local report = require "femlod.report"
--   print(report.text(mesh:quality(), "part.obj"))    -- multi-line report with histogram
--   print(report.header()); print(report.row(q, "part.obj", "original"))  -- a Table 1 row
--   print(report.fields(q))                            -- "key value" lines, sorted
--   print(report.stats(h:stats()))                     -- how a simplification went
--   local r = report.report(mesh, { reference = m0, html = "part.html" })  -- also femlod.report
--   report.sweep_page(manifest, "sweep.html")          -- what `femlod sweep` writes
--   local ticks, step = report.ticks(0, 1586)          -- 0 500 1000 1500 2000: the pages' axes
--
-- Each function also takes a femlod.Mesh instead of its quality table
-- (report.stats a femlod.Hierarchy instead of its stats table).
-- The text functions are pure Lua over the quality table's fields; report()
-- and sweep_page() build HTML pages (html.lua's part below).

local type, error, pairs, ipairs, tostring, getmetatable = type, error, pairs, ipairs, tostring, getmetatable
local pcall = pcall
local format, rep, concat, sort = string.format, string.rep, table.concat, table.sort
local byte, sub, gsub = string.byte, string.sub, string.gsub
local pack, unpack = string.pack, string.unpack
local floor, ceil, max, min, sqrt, abs, huge = math.floor, math.ceil, math.max, math.min, math.sqrt, math.abs, math.huge
local log = math.log
local tonumber = tonumber
local function log10(x) return log(x, 10) end
local mtype = math.type
-- A host may have removed io, os or package (a sandbox): the text
-- functions work without them, the pages say what is missing.
local io_, os_, package_ = io or {}, os or {}, package or {}
local io_open, os_getenv = io_.open, os_.getenv
local loaded = package_.loaded or {}
local require = require

local _ENV = nil -- no global access after this point (LPeg's re.lua)

local M = {}

-- A quality table, or a Mesh whose quality is computed; blames the caller of
-- the public function (level 3: this function, the public one, its caller).
local function quality_of(q, fname)
  local mt = type(q) == "userdata" and getmetatable(q)
  local tname = type(mt) == "table" and mt.__name
  if tname == "femlod.Mesh" then return q:quality() end
  if type(q) ~= "table" or type(q.triangles) ~= "number" then
    error(format("bad argument #1 to '%s' (quality table or femlod.Mesh expected, got %s)",
      fname, type(q) == "table" and "table without quality fields" or tname or type(q)), 3)
  end
  return q
end

local function check_string(v, n, fname)
  if v ~= nil and type(v) ~= "string" then
    error(format("bad argument #%d to '%s' (string expected, got %s)", n, fname, type(v)), 3)
  end
end

-- Numbers in the report: enough digits to compare with published figures,
-- few enough to read. %g, so no locale-dependent thousands separators.
local function num(x)
  if mtype(x) == "integer" then return format("%d", x) end
  return format("%.6g", x)
end

local function point(p)
  return format("(%s, %s, %s)", num(p[1]), num(p[2]), num(p[3]))
end

local function plural(n, one, many)
  return format("%d %s", n, n == 1 and one or many or one .. "s")
end

-- The paper's Table 1 columns: model (dimensions), state, elements,
-- stretch (avg, min), size (max), valence (max).
function M.header()
  return "model (H x W x D) | state | elements | stretch (avg, min) | size (max) | valence (max)"
end

function M.row(q, name, state)
  q = quality_of(q, "row")
  check_string(name, 2, "row")
  check_string(state, 3, "row")
  local b = q.bbox
  local dims = format("%.4g x %.4g x %.4g", b.max[1] - b.min[1], b.max[2] - b.min[2],
    b.max[3] - b.min[3])
  return format("%s (%s) | %s | %d | %.3f, %.3f | %.4g | %d", name or "mesh", dims, state or "-",
    q.triangles, q.stretch_avg, q.stretch_min, q.size_max, q.valence_max)
end

local BAR = 40

-- The stretch histogram, one line per bin: bin k holds [k/10, (k+1)/10),
-- the last one is closed at 1.
local function histogram_lines(h, out)
  local total, most = 0, 0
  for _, n in ipairs(h) do total, most = total + n, max(most, n) end
  local nbins = #h
  for k, n in ipairs(h) do
    local lo, hi = (k - 1) / nbins, k / nbins
    local bar = most > 0 and rep("#", floor(n * BAR / most + 0.5)) or ""
    local pct = total > 0 and 100 * n / total or 0
    out[#out + 1] = format("    [%.1f, %.1f%s %8d %5.1f%%%s", lo, hi, k == nbins and "]" or ")",
      n, pct, bar ~= "" and "  " .. bar or "")
  end
end

-- max_deviation (optional): the bound the mesh was made with; a measured
-- deviation above it is flagged. remaining (optional): a line on what breaks
-- a threshold and why (report() gives it from mesh:census).
function M.text(q, name, max_deviation, remaining)
  q = quality_of(q, "text")
  check_string(name, 2, "text")
  local out = {}
  local function line(label, fmt, ...)
    out[#out + 1] = format("  %-11s " .. fmt, label, ...)
  end
  out[1] = format("%s: %s, %s", name or "mesh", plural(q.triangles, "triangle"),
    plural(q.vertices, "vertex", "vertices"))
  line("stretch", "avg %s  min %s  max %s", num(q.stretch_avg), num(q.stretch_min),
    num(q.stretch_max))
  line("size", "avg %s  min %s  max %s (longest edge)", num(q.size_avg), num(q.size_min),
    num(q.size_max))
  line("valence", "avg %s  max %s", num(q.valence_avg), num(q.valence_max))
  line("angles", "min %s  max %s (degrees)", num(q.angle_min), num(q.angle_max))
  line("area", "%s", num(q.area))
  line("bbox", "%s - %s", point(q.bbox.min), point(q.bbox.max))
  line("topology", "%s, %s, %s; %s, %s", q.closed and "closed" or "open",
    q.manifold and "manifold" or "non-manifold", q.oriented and "oriented" or "not oriented",
    plural(q.components, "component"), plural(q.edges or 0, "edge"))
  line("edges", "%d boundary, %d non-manifold, %d inconsistent", q.boundary_edges,
    q.nonmanifold_edges, q.inconsistent_edges)
  line("triangles", "%d degenerate, %d duplicate", q.degenerate, q.duplicate)
  line("vertices", "%d non-manifold, %d isolated", q.nonmanifold_vertices,
    q.isolated_vertices or 0)
  if q.hausdorff then
    line("hausdorff", "%s (%s of the reference's diagonal; forward %s, backward %s)",
      num(q.hausdorff), num(q.hausdorff_rel), num(q.hausdorff_forward), num(q.hausdorff_backward))
    if type(max_deviation) == "number" then
      line("deviation", q.hausdorff > max_deviation and "EXCEEDS max_deviation %s (%.3g times it)"
        or "within max_deviation %s (%.3g of it)", num(max_deviation), q.hausdorff / max_deviation)
    end
  end
  if type(remaining) == "string" then line("breaking", "%s", remaining) end
  out[#out + 1] = "  stretch histogram:"
  histogram_lines(q.histogram, out)
  return concat(out, "\n")
end

-- Every scalar field as "key value", sorted by key (pairs order is not
-- repeatable), bbox and histogram flattened: for scripts and diffs.
function M.fields(q)
  q = quality_of(q, "fields")
  local flat = {}
  for k, v in pairs(q) do
    if type(v) ~= "table" then flat[k] = v end
  end
  flat.bbox_min = point(q.bbox.min)
  flat.bbox_max = point(q.bbox.max)
  local hist = {}
  for i, n in ipairs(q.histogram) do hist[i] = format("%d", n) end
  flat.histogram = concat(hist, " ")
  local keys = {}
  for k in pairs(flat) do keys[#keys + 1] = k end
  sort(keys)
  local out = {}
  for i, k in ipairs(keys) do
    local v = flat[k]
    out[i] = format("%s %s", k, type(v) == "number" and num(v) or tostring(v))
  end
  return concat(out, "\n")
end

-- {====== simplification statistics (h:stats())

local REJECTED = { "tolerance", "deviation", "stretch", "size", "valence", "foldover", "topology",
  "intersection" }
local THRESHOLDS = { "target", "tolerance", "max_deviation", "min_stretch", "max_size", "max_valence",
  "feature_angle", "feature_weight", "max_normal_change" }

local function stats_of(s, fname)
  local mt = type(s) == "userdata" and getmetatable(s)
  local tname = type(mt) == "table" and mt.__name
  if tname == "femlod.Hierarchy" then return s:stats() end
  if type(s) ~= "table" or type(s.stop_reason) ~= "string" or type(s.rejected) ~= "table"
      or type(s.thresholds) ~= "table" then
    error(format("bad argument #1 to '%s' (stats table or femlod.Hierarchy expected, got %s)",
      fname, type(s) == "table" and "table without stats fields" or tname or type(s)), 3)
  end
  return s
end

local REASONS = { "corner", "boundary", "fixed", "deviation", "stretch", "valence", "foldover",
  "topology", "intersection", "depth", "untried", "fixable" }
local FORCED = { corner = true, boundary = true }

-- " (forced 2: corner 2 at 6.5-6.9 degrees; fixable 3, topology 1)" from a
-- table of counts by reason (femlod_improve_reason names), "" when empty;
-- s (optional) holds corner_angle_min/max.
function M.reasons(by, s)
  if type(by) ~= "table" then return "" end
  local forced, nf, other = {}, 0, {}
  for _, k in ipairs(REASONS) do
    local n = by[k] or 0
    if n > 0 then
      if FORCED[k] then
        nf = nf + n
        forced[#forced + 1] = format("%s %d", k, n)
      else
        other[#other + 1] = format("%s %d", k, n)
      end
    end
  end
  if nf == 0 and #other == 0 then return "" end
  local parts = {}
  if nf > 0 then
    local ang = ""
    if s and s.corner_angle_max then
      local lo, hi = format("%.1f", s.corner_angle_min), format("%.1f", s.corner_angle_max)
      ang = lo == hi and format(" at %s degrees", hi) or format(" at %s-%s degrees", lo, hi)
    end
    parts[1] = format("forced %d: %s%s", nf, concat(forced, ", "), ang)
  end
  if #other > 0 then parts[#parts + 1] = "not forced: " .. concat(other, ", ") end
  return " (" .. concat(parts, "; ") .. ")"
end

-- Why and after how much work it stopped; what the improve stage did (when
-- it ran); at a stop with no valid edge, the checks refusing the edges left
-- (each once); which checks refused collapses (counts of edge evaluations);
-- the output triangles left breaking a threshold, by reason (and vertices
-- above max_valence, when any); the thresholds in force ("off" when
-- switched off, target "none" when there was none).
function M.stats(s)
  s = stats_of(s, "stats")
  local rej, th = {}, {}
  for i, k in ipairs(REJECTED) do rej[i] = format("%s %d", k, s.rejected[k] or 0) end
  for i, k in ipairs(THRESHOLDS) do
    local v = s.thresholds[k]
    local off = k == "target" and "none" or "off"
    th[i] = format("%s %s", k, v == false and off or type(v) == "number" and num(v) or "?")
  end
  local lines = {
    format("stop: %s; %s (%d in the pre-phase%s) in %.3f s", s.stop_reason,
      plural(s.collapses, "collapse"), s.prephase_collapses,
      (s.fast_collapses or 0) > 0 and format(", %d in fast passes on %s", s.fast_collapses,
        plural(s.threads or 1, "thread")) or "",
      s.seconds),
  }
  if s.improved then
    lines[#lines + 1] = format("improve stage first: %s on the input, %s handed on, in %.3f s",
      plural(s.improve_operations, "operation"), plural(s.improve_triangles, "triangle"),
      s.improve_seconds)
  end
  -- the last full evaluation at a stop with no valid edge: each edge once
  if s.stop_rejected then
    local by, n = {}, 0
    for _, k in ipairs(REJECTED) do
      local c = s.stop_rejected[k] or 0
      n = n + c
      if c > 0 then by[#by + 1] = { k, c } end
    end
    -- the edges that pass it fail the checks made when taken from the queue
    if (s.stop_taken or 0) > 0 then
      n = n + s.stop_taken
      by[#by + 1] = { "intersection or deviation", s.stop_taken }
    end
    sort(by, function(a, b) return a[2] > b[2] or (a[2] == b[2] and a[1] < b[1]) end)
    local st = s.stop_topology
    for i, e in ipairs(by) do
      by[i] = format("%s %d", e[1], e[2])
      if e[1] == "topology" and st then
        local parts = {}
        for _, k in ipairs({ "features", "link", "boundary", "nonmanifold" }) do
          if (st[k] or 0) > 0 then parts[#parts + 1] = format("%s %d", k, st[k]) end
        end
        if #parts > 0 then by[i] = by[i] .. " (" .. concat(parts, ", ") .. ")" end
      end
    end
    if n > 0 then
      lines[#lines + 1] = format("stopped at %d: each of the %s left breaks a check: %s", s.triangles,
        plural(n, "edge"), concat(by, ", "))
    end
  end
  lines[#lines + 1] = "rejected: " .. concat(rej, ", ")
  lines[#lines + 1] = format("violating output: %s%s; dropped degenerate: %d",
    plural(s.violating_input, "triangle"), M.reasons(s.violating_by, s), s.dropped_degenerate)
  if (s.violating_valence or 0) > 0 then
    lines[#lines + 1] = format("valence above max: %s%s", plural(s.violating_valence, "vertex", "vertices"),
      M.reasons(s.violating_valence_by))
  end
  lines[#lines + 1] = "thresholds: " .. concat(th, ", ")
  return concat(lines, "\n")
end

-- }======

-- {====== HTML pages: the Table 1 row, histograms as inline SVG, the mesh in
-- an interactive viewer (@google/model-viewer, inlined so the page works
-- offline), and the sweep page comparing all points.

local function esc(v)
  return (gsub(tostring(v), "[&<>\"']", { ["&"] = "&amp;", ["<"] = "&lt;", [">"] = "&gt;",
    ['"'] = "&quot;", ["'"] = "&#39;" }))
end

-- Coordinates in SVG: two decimals, and -0 printed as 0.
local function c2(x)
  local s = format("%.2f", x)
  return s == "-0.00" and "0.00" or s
end

local B64 = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/"
local B64T = {}
for i = 1, 64 do B64T[i - 1] = sub(B64, i, i) end

local function base64(data)
  local out, n = {}, #data
  for i = 1, n - 2, 3 do
    local a, b, c = byte(data, i, i + 2)
    local v = a * 65536 + b * 256 + c
    out[#out + 1] = B64T[v // 262144] .. B64T[v // 4096 % 64] .. B64T[v // 64 % 64] .. B64T[v % 64]
  end
  local r = n % 3
  if r == 1 then
    local v = byte(data, n) * 65536
    out[#out + 1] = B64T[v // 262144] .. B64T[v // 4096 % 64] .. "=="
  elseif r == 2 then
    local a, b = byte(data, n - 1, n)
    local v = a * 65536 + b * 256
    out[#out + 1] = B64T[v // 262144] .. B64T[v // 4096 % 64] .. B64T[v // 64 % 64] .. "="
  end
  return concat(out)
end
M.base64 = base64

-- Viridis at 0, 0.25, 0.5, 0.75, 1 (matplotlib, CC0): the scale of the
-- glTF colours (formats.md), for legends.
local VIRIDIS = { "#440154", "#3b528b", "#21918c", "#5ec962", "#fde725" }

-- {=== axes: ticks at "nice numbers" (1, 2, 2.5 or 5 times a power of ten),
-- covering the data, so that every axis reaches past its largest value.

-- A step near span / n, rounded up to a nice number.
local function nice_step(span, n)
  if not (span > 0) then return 1 end
  local raw = span / n
  local p = 10 ^ floor(log10(raw))
  for _, m in ipairs { 1, 2, 2.5, 5, 10 } do
    if m * p >= raw * (1 - 1e-9) then return m * p end
  end
  return 10 * p
end

-- Decimals a tick label needs at this step.
local function step_decimals(step)
  local d = 0
  while d < 12 and abs(step * 10 ^ d - floor(step * 10 ^ d + 0.5)) > 1e-6 * step * 10 ^ d do d = d + 1 end
  return d
end

-- ticks(lo, hi [, n]): about n (default 5) intervals of a nice step from a
-- multiple of the step at or below lo to one at or above hi. Returns the
-- list of values and the step.
function M.ticks(lo, hi, n)
  if type(lo) ~= "number" or type(hi) ~= "number" or lo ~= lo or hi ~= hi or lo == huge or hi == huge
      or lo == -huge or hi == -huge then
    error("bad argument to 'ticks' (finite numbers expected)", 2)
  end
  n = n or 5
  if hi < lo then lo, hi = hi, lo end
  if hi == lo then
    local d = lo ~= 0 and abs(lo) * 0.1 or 1
    lo, hi = lo - d, hi + d
  end
  local step = nice_step(hi - lo, n)
  local a, b = floor(lo / step + 1e-9), ceil(hi / step - 1e-9)
  local dec = step_decimals(step)
  local list = {}
  for k = a, b do
    local v = tonumber(format("%." .. dec .. "f", k * step))
    list[#list + 1] = v == 0 and 0 or v
  end
  return list, step
end

-- A tick's label: as many decimals as the step has, no more.
function M.tick_text(v, step)
  local s = format("%." .. step_decimals(step) .. "f", v)
  if s:match("^%-0%.?0*$") then s = s:sub(2) end
  return s
end
local tick_text = M.tick_text

-- }===

-- A histogram: opts.bins {lo, hi, count, tip} on a continuous x axis
-- [x0, x1] with ticks xticks (values, step); y linear with nice ticks
-- covering the largest count, or opts.log: log(1 + count), ticks at powers
-- of ten, so that a bin of one triangle is still a visible bar.
-- opts.counts prints the count over every bar; opts.mark {x, text} draws a
-- dashed line at x (a threshold). Returns the <svg> element.
local function bar_chart(o)
  local W, H, L, R, T, Bm = 420, 250, 64, 12, 40, 46
  local pw, ph = W - L - R, H - T - Bm
  local most = 0
  for _, b in ipairs(o.bins) do most = max(most, b[3]) end
  local yt, ystep, ytop, Yv
  if o.log then
    local k = max(1, ceil(log10(max(most, 1)) - 1e-9))
    yt, ystep, ytop = {}, 1, 10 ^ k
    -- 1, 10, 100, ...: no 0, which would sit a few pixels under the 1
    for e = 0, k do yt[#yt + 1] = floor(10 ^ e + 0.5) end
    Yv = function(c) return c > 0 and log10(1 + c) / log10(1 + ytop) or 0 end
  else
    yt, ystep = M.ticks(0, max(most, 1), 4)
    if most < 4 then yt, ystep = M.ticks(0, max(most, 1), max(most, 1)) end
    ytop = yt[#yt]
    Yv = function(c) return c / ytop end
  end
  local x0, x1 = o.x0, o.x1
  local function X(x) return L + pw * (x - x0) / (x1 - x0) end
  local function Y(f) return T + ph - ph * f end
  local out = { format('<svg id="%s" class="chart" xmlns="http://www.w3.org/2000/svg" viewBox="0 0 %d %d" '
    .. 'width="%d" height="%d" role="img" aria-label="%s">', o.id, W, H, W, H, esc(o.title)) }
  out[#out + 1] = format('<text x="%d" y="16" class="title">%s</text>', W // 2, esc(o.title))
  out[#out + 1] = format('<line x1="%d" y1="%d" x2="%d" y2="%d" class="axis"/>', L, T + ph, L + pw, T + ph)
  out[#out + 1] = format('<line x1="%d" y1="%d" x2="%d" y2="%d" class="axis"/>', L, T, L, T + ph)
  local last_y = huge
  for _, v in ipairs(yt) do
    local y = Y(Yv(v))
    out[#out + 1] = format('<line x1="%d" y1="%s" x2="%d" y2="%s" class="grid"/>', L, c2(y), L + pw, c2(y))
    -- on the log scale 0 and 1 sit close: a label only where it has room
    if last_y - y >= 11 then
      out[#out + 1] = format('<text x="%d" y="%s" class="tick ytick" text-anchor="end">%s</text>', L - 6, c2(y + 4),
        o.log and format("%d", v) or tick_text(v, ystep))
      last_y = y
    end
  end
  for _, b in ipairs(o.bins) do
    local h = ph * Yv(b[3])
    if b[3] > 0 and h < 2 then h = 2 end
    local xa, xb = X(b[1]), X(b[2])
    out[#out + 1] = format('<rect class="bar" x="%s" y="%s" width="%s" height="%s"><title>%s: %d</title></rect>',
      c2(xa + 1), c2(T + ph - h), c2(max(xb - xa - 2, 1)), c2(h), esc(b[4]), b[3])
    if o.counts then
      out[#out + 1] = format('<text x="%s" y="%s" class="count" text-anchor="middle">%d</text>', c2((xa + xb) / 2),
        c2(T + ph - h - 3), b[3])
    end
  end
  local xt, xstep = o.xticks[1], o.xticks[2]
  for _, v in ipairs(xt) do
    if v >= x0 - 1e-9 and v <= x1 + 1e-9 then
      out[#out + 1] = format('<text x="%s" y="%d" class="tick xtick" text-anchor="middle">%s</text>', c2(X(v)),
        T + ph + 17, tick_text(v, xstep))
    end
  end
  if o.mark then
    local x = X(o.mark[1])
    out[#out + 1] = format('<line id="%s-mark" x1="%s" y1="%d" x2="%s" y2="%d" class="mark"/>', o.id, c2(x), T - 6,
      c2(x), T + ph)
    out[#out + 1] = format('<text x="%s" y="%d" class="marklabel" text-anchor="%s">%s</text>', c2(x + 3), T - 8,
      "start", esc(o.mark[2]))
  end
  out[#out + 1] = format('<text x="%d" y="%d" class="label" text-anchor="middle">%s</text>', L + pw // 2, H - 8,
    esc(o.xlabel))
  if o.ylabel then
    out[#out + 1] = format('<text x="12" y="%d" class="label" text-anchor="middle" transform="rotate(-90 12 %d)">%s'
      .. '</text>', T + ph // 2, T + ph // 2, esc(o.ylabel))
  end
  out[#out + 1] = "</svg>"
  return concat(out, "\n")
end

-- Categorical colours for the series of a sweep (Okabe and Ito's palette,
-- distinguishable with the common colour-vision deficiencies).
local SERIES = { "#0072b2", "#e69f00", "#009e73", "#cc79a7", "#56b4e9", "#d55e00", "#f0e442", "#000000" }

-- Point labels placed where they overlap no other label and no dot: the
-- first free place of eight around the dot, or none (the dot's tooltip
-- still names it). Boxes are estimated from the font (10 px, about 6 px a
-- character).
local function place_labels(items, dots)
  local placed = {}
  local function hit(a, b)
    return a[1] < b[3] and b[1] < a[3] and a[2] < b[4] and b[2] < a[4]
  end
  local out = {}
  for _, it in ipairs(items) do
    local w, h = 6 * #it.text, 10
    local cands = { { 7, -4 }, { -7 - w, -4 }, { -w / 2, -8 }, { -w / 2, 14 }, { 7, 8 }, { -7 - w, 8 },
      { 7, -14 }, { -7 - w, -14 } }
    for _, c in ipairs(cands) do
      local x, y = it.x + c[1], it.y + c[2]
      local box = { x, y - h + 2, x + w, y + 2 }
      local free = box[1] >= it.left and box[3] <= it.right and box[2] >= it.top and box[4] <= it.bottom
      for _, p in ipairs(placed) do
        if not free then break end
        if hit(box, p) then free = false end
      end
      for _, d in ipairs(dots) do
        if not free then break end
        if hit(box, { d[1] - 5, d[2] - 5, d[1] + 5, d[2] + 5 }) then free = false end
      end
      if free then
        placed[#placed + 1] = box
        out[#out + 1] = { x = x, y = y, text = it.text }
        break
      end
    end
  end
  return out
end

-- A scatter plot: points {x, y, tip, label, series}; series (1..#names,
-- coloured, joined by a line in x order, named in a legend) when names
-- is given. Returns the <svg> element.
local function scatter(id, title, pts, xlabel, ylabel, names)
  local W, H, L, R, T, Bm = 420, 270, 70, 16, 28, 46
  local xmin, xmax, ymin, ymax = huge, -huge, huge, -huge
  local shown = {}
  for _, p in ipairs(pts) do
    if type(p[1]) == "number" and type(p[2]) == "number" then
      shown[#shown + 1] = p
      xmin, xmax = min(xmin, p[1]), max(xmax, p[1])
      ymin, ymax = min(ymin, p[2]), max(ymax, p[2])
    end
  end
  local out = { format('<svg id="%s" class="chart" xmlns="http://www.w3.org/2000/svg" viewBox="0 0 %d %d" '
    .. 'width="%d" height="%d" role="img" aria-label="%s">', id, W, H, W, H, esc(title)) }
  out[#out + 1] = format('<text x="%d" y="18" class="title">%s</text>', W // 2, esc(title))
  if #shown == 0 then
    -- Nothing to plot: say so, with no invented axis.
    out[#out + 1] = format('<text x="%d" y="%d" class="empty" text-anchor="middle">no point has a value to plot</text>',
      W // 2, H // 2)
    out[#out + 1] = "</svg>"
    return concat(out, "\n")
  end
  local xt, xs = M.ticks(xmin, xmax, 4)
  local yt, ys = M.ticks(ymin, ymax, 4)
  -- the plot reaches a little past the end ticks, so that no dot sits on an axis
  local px, py = (xt[#xt] - xt[1]) * 0.04, (yt[#yt] - yt[1]) * 0.05
  local x0, x1, y0, y1 = xt[1] - px, xt[#xt] + px, yt[1] - py, yt[#yt] + py
  local pw, ph = W - L - R, H - T - Bm
  local function X(x) return L + pw * (x - x0) / (x1 - x0) end
  local function Y(y) return T + ph - ph * (y - y0) / (y1 - y0) end
  out[#out + 1] = format('<line x1="%d" y1="%d" x2="%d" y2="%d" class="axis"/>', L, T + ph, L + pw, T + ph)
  out[#out + 1] = format('<line x1="%d" y1="%d" x2="%d" y2="%d" class="axis"/>', L, T, L, T + ph)
  for _, v in ipairs(xt) do
    out[#out + 1] = format('<text x="%s" y="%d" class="tick xtick" text-anchor="middle">%s</text>', c2(X(v)),
      T + ph + 17, tick_text(v, xs))
  end
  for _, v in ipairs(yt) do
    out[#out + 1] = format('<line x1="%d" y1="%s" x2="%d" y2="%s" class="grid"/>', L, c2(Y(v)), L + pw, c2(Y(v)))
    out[#out + 1] = format('<text x="%d" y="%s" class="tick ytick" text-anchor="end">%s</text>', L - 6,
      c2(Y(v) + 4), tick_text(v, ys))
  end
  if names then
    for s = 1, #names do
      local line = {}
      for _, p in ipairs(shown) do
        if p[5] == s then line[#line + 1] = p end
      end
      sort(line, function(a, b) return a[1] < b[1] end)
      if #line > 1 then
        local d = {}
        for i, p in ipairs(line) do d[i] = c2(X(p[1])) .. "," .. c2(Y(p[2])) end
        out[#out + 1] = format('<polyline class="series" points="%s" style="stroke:%s"/>', concat(d, " "),
          SERIES[(s - 1) % #SERIES + 1])
      end
    end
  end
  local dots, items = {}, {}
  for _, p in ipairs(shown) do
    local cx, cy = X(p[1]), Y(p[2])
    dots[#dots + 1] = { cx, cy }
    local fill = names and p[5] and format(' style="fill:%s"', SERIES[(p[5] - 1) % #SERIES + 1]) or ""
    out[#out + 1] = format('<circle class="dot"%s cx="%s" cy="%s" r="5"><title>%s</title></circle>', fill, c2(cx),
      c2(cy), esc(p[3] or ""))
    if p[4] then
      items[#items + 1] = { x = cx, y = cy, text = p[4], left = L + 1, right = L + pw, top = T, bottom = T + ph - 1 }
    end
  end
  for _, l in ipairs(place_labels(items, dots)) do
    out[#out + 1] = format('<text x="%s" y="%s" class="dotlabel">%s</text>', c2(l.x), c2(l.y), esc(l.text))
  end
  out[#out + 1] = format('<text x="%d" y="%d" class="label" text-anchor="middle">%s</text>', L + pw // 2, H - 8,
    esc(xlabel))
  out[#out + 1] = format('<text x="14" y="%d" class="label" text-anchor="middle" transform="rotate(-90 14 %d)">%s</text>',
    T + ph // 2, T + ph // 2, esc(ylabel))
  out[#out + 1] = "</svg>"
  return concat(out, "\n")
end

local CSS = [[
body { font: 14px/1.4 system-ui, sans-serif; margin: 24px; color: #222; background: #fff; }
h1 { font-size: 20px; margin: 0 0 12px; }
h2 { font-size: 16px; margin: 20px 0 8px; }
table { border-collapse: collapse; margin: 8px 0; }
th, td { border: 1px solid #ccc; padding: 3px 8px; text-align: right; }
th { background: #f3f3f3; }
td.name, th.name { text-align: left; }
.charts { display: flex; flex-wrap: wrap; gap: 12px; }
.chart { border: 1px solid #ddd; background: #fff; }
.chart .title { font-size: 13px; font-weight: 600; text-anchor: middle; }
.chart .tick { font-size: 10px; fill: #555; }
.chart .label { font-size: 11px; fill: #333; }
.chart .axis { stroke: #444; stroke-width: 1; }
.chart .bar { fill: #3b528b; }
.chart .dot { fill: #21918c; stroke: #222; stroke-width: 0.5; }
.chart .dotlabel { font-size: 10px; fill: #333; }
.chart .grid { stroke: #eee; stroke-width: 1; }
.chart .count { font-size: 9px; fill: #222; }
.chart .mark { stroke: #d55e00; stroke-width: 1.5; stroke-dasharray: 4 3; }
.chart .marklabel { font-size: 10px; fill: #d55e00; }
.chart .series { fill: none; stroke-width: 1.5; opacity: 0.6; }
.chart .empty { font-size: 12px; fill: #666; }
.top { display: flex; flex-wrap: wrap; gap: 16px; align-items: flex-start; }
.view { flex: 0 0 642px; width: 642px; }
.side { flex: 1 1 360px; min-width: 0; }
.side h2 { margin-top: 0; }
.side table { font-size: 13px; }
#viewer { width: 640px; height: 480px; background: #f0f0f0; border: 1px solid #ddd; }
.legend { display: flex; align-items: center; gap: 8px; font-size: 12px; }
.series-legend { display: flex; flex-wrap: wrap; gap: 14px; font-size: 13px; margin: 4px 0 8px; }
.series-legend span.swatch { display: inline-block; width: 12px; height: 12px; border-radius: 6px;
  border: 1px solid #222; margin-right: 5px; vertical-align: -1px; }
.note { color: #666; font-size: 12px; }
.failed { color: #b00; }
]]

local function page_head(title)
  return concat({ '<!DOCTYPE html>', '<html lang="en">', '<head>', '<meta charset="utf-8">',
    '<meta name="generator" content="femlod">', "<title>" .. esc(title) .. "</title>",
    "<style>" .. CSS .. "</style>", "</head>", "<body>" }, "\n")
end

-- Writes text to path atomically through femlod.write_file (a temporary
-- file beside it, renamed over it; the sandbox's folders apply), raising the
-- error at level. femlod.write_file logs the file for a sweep's record.
local function write_atomic(path, text, level)
  local femlod = loaded["femlod"]
  if not femlod and require then
    local ok, m = pcall(require, "femlod")
    femlod = ok and m or nil
  end
  if not (type(femlod) == "table" and femlod.write_file) then
    error("HTML pages need the femlod module", level)
  end
  local ok, err = pcall(femlod.write_file, path, text)
  if not ok then error(err, level) end
end

-- The whole file, or nil and why not (the system's message without the path).
local function read_all(path)
  if not io_open then return nil, "no io library" end
  local ok, f, err = pcall(io_open, path, "rb")
  if not ok then return nil, tostring(f) end
  if not f then return nil, (gsub(tostring(err), "^.*: ", "")) end
  local data, rerr = f:read("a")
  f:close()
  if not data then return nil, (gsub(tostring(rerr), "^.*: ", "")) end
  return data
end

-- Where model-viewer.min.js is: opts.viewer, $FEMLOD_MODEL_VIEWER, then the
-- places the build and the install put it (femlod._VIEWER_PATHS). A variable
-- set to a file that cannot be read is an error, not a reason to take
-- another copy: whoever set it meant that file.
local function find_viewer(opt)
  if type(opt) == "string" then
    local js = read_all(opt)
    if not js then error(format("viewer: cannot read '%s'", opt), 3) end
    return js, opt
  end
  local tried = {}
  local env = os_getenv and os_getenv("FEMLOD_MODEL_VIEWER")
  if env and env ~= "" then
    local js, why = read_all(env)
    if js then return js, env end
    error(format("FEMLOD_MODEL_VIEWER is '%s', which cannot be read (%s): set it to the path of "
      .. "model-viewer.min.js, or unset it to use femlod's own copy", env, why), 3)
  end
  local ok, femlod = false, nil
  if require then ok, femlod = pcall(require, "femlod") end
  if ok and type(femlod) == "table" and type(femlod._VIEWER_PATHS) == "table" then
    for _, p in ipairs(femlod._VIEWER_PATHS) do tried[#tried + 1] = p end
  end
  if ok and type(femlod) == "table" and femlod._viewer_js then
    local js, p = femlod._viewer_js()
    if js then return js, p end
  end
  error("the 3D viewer model-viewer.min.js was not found (looked in: " .. concat(tried, ", ")
    .. "); set FEMLOD_MODEL_VIEWER or the viewer option to its path, or viewer = false", 3)
end

-- Per-triangle size (longest edge) and stretch (sqrt(12) * inradius /
-- longest edge), and per-vertex valence (distinct neighbours through
-- edges), as the quality report defines them.
local SQRT12 = sqrt(12)
local function element_measures(mesh)
  local P, Tr = mesh:positions(), mesh:triangles()
  local sizes, stretch, nb = {}, {}, {}
  local function d(a, b)
    local x, y, z = a[1] - b[1], a[2] - b[2], a[3] - b[3]
    return sqrt(x * x + y * y + z * z)
  end
  local edges = {}
  local nv = #P
  for i, t in ipairs(Tr) do
    local a, b, c = P[t[1]], P[t[2]], P[t[3]]
    local ab, bc, ca = d(a, b), d(b, c), d(c, a)
    local longest = max(ab, bc, ca)
    sizes[i] = longest
    local ux, uy, uz = b[1] - a[1], b[2] - a[2], b[3] - a[3]
    local vx, vy, vz = c[1] - a[1], c[2] - a[2], c[3] - a[3]
    local cx, cy, cz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx
    local area2 = sqrt(cx * cx + cy * cy + cz * cz)
    local perim = ab + bc + ca
    stretch[i] = (longest > 0 and perim > 0) and SQRT12 * (area2 / perim) / longest or 0
    for k = 1, 3 do
      local u, v = t[k], t[k % 3 + 1]
      if u > v then u, v = v, u end
      local key = u * (nv + 1) + v
      if u ~= v and not edges[key] then
        edges[key] = true
        nb[u] = (nb[u] or 0) + 1
        nb[v] = (nb[v] or 0) + 1
      end
    end
  end
  return sizes, nb, stretch
end

-- Size bins of a nice width from 0 to a nice edge at or above the
-- largest size (at most 10 bins): every edge a round number.
local function size_bins(sizes, smax)
  local step = smax > 0 and nice_step(smax, 10) or 1
  local nbins = smax > 0 and max(1, ceil(smax / step - 1e-9)) or 10
  if nbins * step < smax then nbins = nbins + 1 end
  local counts, edges = {}, {}
  for k = 1, nbins do counts[k] = 0 end
  for _, sz in ipairs(sizes) do
    local k = floor(sz / step) + 1
    if k > nbins then k = nbins end
    counts[k] = counts[k] + 1
  end
  for k = 0, nbins do edges[k + 1] = tonumber(format("%." .. step_decimals(step) .. "f", k * step)) end
  return counts, edges, step
end

local function valence_list(nb)
  local counts, lo, hi = {}, huge, -huge
  for _, v in pairs(nb) do
    counts[v] = (counts[v] or 0) + 1
    lo, hi = min(lo, v), max(hi, v)
  end
  local list = {}
  if lo > hi then return list end
  for v = lo, hi do list[#list + 1] = { valence = v, count = counts[v] or 0 } end
  return list
end

-- The simplifier's default least stretch (femlod.h, tau_ST): the mark on
-- the stretch histogram when the caller names no threshold.
local DEFAULT_MIN_STRETCH = 0.2
-- Meshes above this many triangles are shown in the 3D view through a copy
-- simplified for display: the GLB is inlined in the page (about 110 bytes
-- a triangle in base64), and a page of tens of megabytes loads slowly.
local DEFAULT_DISPLAY_TRIANGLES = 20000

-- {=== a compact GLB for the display copy: welded vertices, one colour a
-- vertex (the least stretch of the triangles around it, on viridis, 8 bits
-- a channel), 16-bit indices when they fit: about 16 bytes a vertex and 6
-- a triangle, where femlod's own per-triangle colours take 84 a triangle.

-- Matplotlib's viridis (CC0), sRGB, at t = 0, 16/255, ..., 240/255, 1 (the
-- table io_gltf.cpp colours with).
local VIRIDIS17 = {
  { 0.267004, 0.004874, 0.329415 }, { 0.282327, 0.094955, 0.417331 }, { 0.278826, 0.175490, 0.483397 },
  { 0.258965, 0.251537, 0.524736 }, { 0.229739, 0.322361, 0.545706 }, { 0.199430, 0.387607, 0.554642 },
  { 0.172719, 0.448791, 0.557885 }, { 0.149039, 0.508051, 0.557250 }, { 0.127568, 0.566949, 0.550556 },
  { 0.120638, 0.625828, 0.533488 }, { 0.157851, 0.683765, 0.501686 }, { 0.246070, 0.738910, 0.452024 },
  { 0.369214, 0.788888, 0.382914 }, { 0.515992, 0.831158, 0.294279 }, { 0.678489, 0.863742, 0.189503 },
  { 0.845561, 0.887322, 0.099702 }, { 0.993248, 0.906157, 0.143936 },
}

-- Linear RGB bytes of viridis at t (glTF's COLOR_0 is linear).
local function viridis_bytes(t)
  if not (t > 0) then t = 0 elseif t > 1 then t = 1 end
  local u = t * 255
  local k = min(floor(u / 16), 15)
  local t0, t1 = k * 16, k == 15 and 255 or (k + 1) * 16
  local f = (u - t0) / (t1 - t0)
  local a, b = VIRIDIS17[k + 1], VIRIDIS17[k + 2]
  local out = {}
  for i = 1, 3 do
    local c = a[i] + f * (b[i] - a[i])
    local l = c <= 0.04045 and c / 12.92 or ((c + 0.055) / 1.055) ^ 2.4
    out[i] = floor(min(max(l, 0), 1) * 255 + 0.5)
  end
  return out[1], out[2], out[3]
end

local function glb_compact(mesh, stretch)
  local P, Tr = mesh:positions(), mesh:triangles()
  local nv, nt = #P, #Tr
  local vmin = {}
  for i, t in ipairs(Tr) do
    local s = stretch[i]
    for k = 1, 3 do
      local v = t[k]
      if not vmin[v] or s < vmin[v] then vmin[v] = s end
    end
  end
  local pos, col, lo, hi = {}, {}, { huge, huge, huge }, { -huge, -huge, -huge }
  for v = 1, nv do
    local p = P[v]
    pos[v] = pack("<fff", p[1], p[2], p[3])
    for k = 1, 3 do
      local x = unpack("<f", pack("<f", p[k]))
      lo[k], hi[k] = min(lo[k], x), max(hi[k], x)
    end
    local r, g, b = viridis_bytes(vmin[v] or 1)
    col[v] = pack("BBBB", r, g, b, 255)
  end
  local wide = nv > 65535
  local ifmt = wide and "<I4I4I4" or "<I2I2I2"
  local idx = {}
  for i, t in ipairs(Tr) do idx[i] = pack(ifmt, t[1] - 1, t[2] - 1, t[3] - 1) end
  local bpos, bcol, bidx = concat(pos), concat(col), concat(idx)
  local pad = rep("\0", (4 - #bidx % 4) % 4)
  local bin = bpos .. bcol .. bidx .. pad
  if nv == 0 then lo, hi = { 0, 0, 0 }, { 0, 0, 0 } end
  local function v3(a) return format("[%.9g,%.9g,%.9g]", a[1], a[2], a[3]) end
  local json = format('{"asset":{"version":"2.0","generator":"femlod report (display copy)",'
    .. '"extras":{"color_by":"stretch","color_scale":{"map":"viridis","min":0.0,"max":1.0,"per":"vertex",'
    .. '"of":"least stretch of the triangles around the vertex"}}},'
    .. '"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],'
    .. '"meshes":[{"name":"femlod","primitives":[{"attributes":{"POSITION":0,"COLOR_0":1},"indices":2,'
    .. '"material":0,"mode":4}]}],'
    .. '"extensionsUsed":["KHR_materials_unlit"],"materials":[{"name":"femlod stretch","doubleSided":true,'
    .. '"extensions":{"KHR_materials_unlit":{}},"pbrMetallicRoughness":{"metallicFactor":0.0}}],'
    .. '"buffers":[{"byteLength":%d}],"bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":%d,"target":34962},'
    .. '{"buffer":0,"byteOffset":%d,"byteLength":%d,"target":34962},'
    .. '{"buffer":0,"byteOffset":%d,"byteLength":%d,"target":34963}],'
    .. '"accessors":[{"bufferView":0,"componentType":5126,"count":%d,"type":"VEC3","min":%s,"max":%s},'
    .. '{"bufferView":1,"componentType":5121,"normalized":true,"count":%d,"type":"VEC4"},'
    .. '{"bufferView":2,"componentType":%d,"count":%d,"type":"SCALAR"}]}',
    #bin, #bpos, #bpos, #bcol, #bpos + #bcol, #bidx, nv, v3(lo), v3(hi), nv, wide and 5125 or 5123, 3 * nt)
  json = json .. rep(" ", (4 - #json % 4) % 4)
  local total = 12 + 8 + #json + 8 + #bin
  return pack("<c4I4I4", "glTF", 2, total) .. pack("<I4c4", #json, "JSON") .. json
    .. pack("<I4c4", #bin, "BIN\0") .. bin
end

-- }===

-- The copy for display, or nil when the simplifier cannot make one.
local function display_copy(mesh, cap)
  local ok, h = pcall(mesh.simplify, mesh, { target = cap, tolerance = false, max_size = false, max_valence = false,
    fast_above = 2 })
  if not ok then return nil end
  local hh <close> = h
  return hh:mesh()
end

local REPORT_KEYS = { reference = true, html = true, name = true, reference_name = true, viewer = true,
  title = true, progress = true, min_stretch = true, display_triangles = true, max_deviation = true }

local function check_opts(opts)
  if opts == nil then return {} end
  if type(opts) ~= "table" then
    error(format("bad argument #2 to 'report' (table expected, got %s)", type(opts)), 3)
  end
  for k in pairs(opts) do
    if not REPORT_KEYS[k] then
      error(format("bad argument #2 to 'report' (unknown option '%s'; valid: display_triangles, html, "
        .. "max_deviation, min_stretch, name, progress, reference, reference_name, title, viewer)", tostring(k)), 3)
    end
  end
  for _, k in ipairs { "html", "name", "reference_name", "title" } do
    if opts[k] ~= nil and type(opts[k]) ~= "string" then
      error(format("bad argument #2 to 'report' (%s: string expected, got %s)", k, type(opts[k])), 3)
    end
  end
  if opts.viewer ~= nil and opts.viewer ~= false and type(opts.viewer) ~= "string" then
    error(format("bad argument #2 to 'report' (viewer: path or false expected, got %s)", type(opts.viewer)), 3)
  end
  local ms = opts.min_stretch
  if ms ~= nil and ms ~= false and not (type(ms) == "number" and ms >= 0 and ms <= 1) then
    error(format("bad argument #2 to 'report' (min_stretch: number in [0, 1] or false expected, got %s)",
      type(ms) == "number" and num(ms) or type(ms)), 3)
  end
  if opts.max_deviation ~= nil and not (type(opts.max_deviation) == "number" and opts.max_deviation > 0) then
    error(format("bad argument #2 to 'report' (max_deviation: positive number expected, got %s)",
      tostring(opts.max_deviation)), 3)
  end
  local dt = opts.display_triangles
  if dt ~= nil and dt ~= false and not (mtype(dt) == "integer" and dt >= 100) then
    error(format("bad argument #2 to 'report' (display_triangles: integer >= 100 or false expected, got %s)",
      type(dt) == "number" and num(dt) or type(dt)), 3)
  end
  if opts.progress ~= nil and type(opts.progress) ~= "function" then
    error(format("bad argument #2 to 'report' (progress: function expected, got %s)", type(opts.progress)), 3)
  end
  local ref = opts.reference
  local mt = type(ref) == "userdata" and getmetatable(ref)
  if ref ~= nil and type(ref) ~= "string" and not (type(mt) == "table" and mt.__name == "femlod.Mesh") then
    error(format("bad argument #2 to 'report' (reference: femlod.Mesh or path expected, got %s)",
      type(mt) == "table" and mt.__name or type(ref)), 3)
  end
  return opts
end

-- The femlod module (the binding), for the helpers that load or write files.
local function binding()
  local femlod = loaded["femlod"]
  if not femlod and require then
    local ok, m = pcall(require, "femlod")
    femlod = ok and m or nil
  end
  return type(femlod) == "table" and femlod or nil
end

-- opts.reference given as a path: the mesh, loaded as femlod.load loads it
-- (the sandbox's folders apply; a sweep's record lists the file as read).
-- Its errors are femlod.load's, at the line of report()'s caller.
local function load_reference(path)
  local femlod = binding()
  if not (femlod and femlod.load) then error("reference: loading a path needs the femlod module", 3) end
  local ok, m = pcall(femlod.load, path)
  if not ok then error(m, 3) end
  return m
end

local function table1(rows)
  local out = { '<table id="table1">', '<tr><th class="name">model (H x W x D)</th><th class="name">state</th>'
    .. '<th>elements</th><th>stretch avg</th><th>stretch min</th><th>size max</th><th>valence max</th></tr>' }
  for _, r in ipairs(rows) do
    local q, b = r.q, r.q.bbox
    out[#out + 1] = format('<tr><td class="name">%s (%.4g x %.4g x %.4g)</td><td class="name">%s</td><td>%d</td>'
      .. '<td>%.3f</td><td>%.3f</td><td>%.4g</td><td>%d</td></tr>', esc(r.name), b.max[1] - b.min[1],
      b.max[2] - b.min[2], b.max[3] - b.min[3], esc(r.state), q.triangles, q.stretch_avg, q.stretch_min,
      q.size_max, q.valence_max)
  end
  out[#out + 1] = "</table>"
  return concat(out, "\n")
end

-- report(mesh [, opts]): the summary of a mesh, and its HTML page when
-- opts.html is given. opts: reference (a Mesh, or the path of a mesh file as
-- `femlod report --reference` takes it: deviation and its own row), name,
-- reference_name (default the file's name for a path), title, html (path), viewer (path of
-- model-viewer.min.js, or false for a page without the 3D view), progress
-- (a function(done) following the deviation from the reference).
function M.report(mesh, opts)
  local mt = type(mesh) == "userdata" and getmetatable(mesh)
  if not (type(mt) == "table" and mt.__name == "femlod.Mesh") then
    error(format("bad argument #1 to 'report' (femlod.Mesh expected, got %s)",
      type(mt) == "table" and mt.__name or type(mesh)), 2)
  end
  opts = check_opts(opts)
  local name = opts.name or "mesh"
  local path_ref = type(opts.reference) == "string" and opts.reference or nil
  local loaded_ref <close> = path_ref and load_reference(path_ref) or nil
  local ref = loaded_ref or opts.reference
  local ref_name = opts.reference_name or (path_ref and path_ref:match("[^/]*$")) or "reference"
  local q = ref and opts.progress and mesh:quality(ref, { progress = opts.progress }) or mesh:quality(ref)
  local sizes, nb, tstretch = element_measures(mesh)
  local nbins = #q.histogram
  local zcounts, zedges, zstep = size_bins(sizes, q.size_max)
  local vlist = valence_list(nb)
  local threshold = opts.min_stretch
  if threshold == nil then threshold = DEFAULT_MIN_STRETCH end
  local below = 0
  if threshold then
    for _, st in ipairs(tstretch) do
      if st < threshold then below = below + 1 end
    end
  end
  -- the honest count: what breaks min_stretch or valence 12, by reason
  -- (mesh:census with the default thresholds and feature angle)
  local census
  if threshold and (below > 0 or q.valence_max > 12) then
    census = mesh:census { min_stretch = threshold }
  end
  local rows = {}
  local rq
  if ref then
    rq = ref:quality()
    rows[1] = { name = ref_name, state = "reference", q = rq }
  end
  rows[#rows + 1] = { name = name, state = ref and "result" or "-", q = q }
  local summary = {
    name = name, quality = q, reference_quality = rq,
    row = M.row(q, name, ref and "result" or nil),
    reference_row = rq and M.row(rq, ref_name, "reference") or nil,
    text = M.text(q, name, opts.max_deviation, census and format(
      "%s below min_stretch %s%s; %s above max_valence %d%s",
      plural(census.remaining.stretch, "triangle"), num(threshold), M.reasons(census.remaining_by.stretch, census),
      plural(census.remaining.valence, "vertex", "vertices"), census.max_valence or 12,
      M.reasons(census.remaining_by.valence))),
    census = census,
    deviation_exceeded = q.hausdorff ~= nil and opts.max_deviation ~= nil and q.hausdorff > opts.max_deviation,
    histograms = { stretch = q.histogram, size = zcounts, size_edges = zedges, size_max = q.size_max,
      valence = vlist },
    min_stretch = threshold or nil, below_min_stretch = threshold and below or nil,
    hausdorff = q.hausdorff, hausdorff_rel = q.hausdorff_rel,
    viewer = false,
  }
  if not opts.html then return summary end

  -- the charts
  local sbins = {}
  for k, n in ipairs(q.histogram) do
    sbins[k] = { (k - 1) / nbins, k / nbins, n,
      format("stretch [%.1f, %.1f%s", (k - 1) / nbins, k / nbins, k == nbins and "]" or ")") }
  end
  local stretch_chart = bar_chart {
    id = "stretch-histogram", title = "Stretch distribution (triangles, log scale)", bins = sbins,
    x0 = 0, x1 = 1, xticks = { M.ticks(0, 1, nbins) }, xlabel = "stretch", ylabel = "triangles", log = true,
    counts = true,
    mark = threshold and { threshold, format("%s %s: %s below", opts.min_stretch and "min_stretch" or "default min_stretch",
      num(threshold), plural(below, "triangle")) } or nil,
  }
  local zbins = {}
  for k, n in ipairs(zcounts) do
    zbins[k] = { zedges[k], zedges[k + 1], n, format("longest edge [%s, %s%s", tick_text(zedges[k], zstep),
      tick_text(zedges[k + 1], zstep), k == #zcounts and "]" or ")") }
  end
  local size_chart = bar_chart {
    id = "size-histogram", title = "Size distribution (triangles)", bins = zbins, x0 = 0, x1 = zedges[#zedges],
    xticks = { M.ticks(0, zedges[#zedges], min(#zcounts, 10)) }, xlabel = "longest edge", ylabel = "triangles",
  }
  local vbins, vx0, vx1, vticks, vstep = {}, 0, 1, { 0, 1 }, 1
  if #vlist > 0 then
    local lo, hi = vlist[1].valence, vlist[#vlist].valence
    vticks, vstep = M.ticks(lo, hi, min(hi - lo + 1, 8))
    if vstep < 1 then vticks, vstep = M.ticks(lo, hi, max(hi - lo, 1)) end
    if vstep < 1 then vticks, vstep = { lo - 1, lo, lo + 1 }, 1 end -- one valence only
    vx0, vx1 = min(vticks[1], lo) - 0.5, max(vticks[#vticks], hi) + 0.5
    for i, e in ipairs(vlist) do
      vbins[i] = { e.valence - 0.5, e.valence + 0.5, e.count, format("valence %d", e.valence) }
    end
  end
  local valence_chart = bar_chart {
    id = "valence-histogram", title = "Valence distribution (vertices)", bins = vbins, x0 = vx0, x1 = vx1,
    xticks = { vticks, vstep }, xlabel = "valence", ylabel = "vertices",
  }

  local js
  if opts.viewer ~= false then js = find_viewer(opts.viewer) end
  local title = opts.title or ("femlod report: " .. name)
  local parts = { page_head(title), "<h1>" .. esc(title) .. "</h1>",
    format('<p class="note">%s; written by femlod</p>', esc(M.text(q, name):match("^[^\n]*"))),
    '<div class="top">' }
  local side = { '<div class="side">', "<h2>Quality (the paper's Table 1 columns)</h2>", table1(rows) }
  if ref then
    side[#side + 1] = format('<p id="deviation">Hausdorff deviation from the reference: <b>%s</b> '
      .. '(%s of the reference\'s bounding-box diagonal; forward %s, backward %s)</p>', num(q.hausdorff),
      num(q.hausdorff_rel), num(q.hausdorff_forward), num(q.hausdorff_backward))
    if summary.deviation_exceeded then
      parts[#parts + 1] = format('<p id="deviation-exceeded"><b>The deviation exceeds max_deviation %s.</b></p>',
        num(opts.max_deviation))
    end
  end
  if threshold then
    side[#side + 1] = format('<p id="below-threshold">%s below %s %s (least stretch %.3f)</p>',
      plural(below, "triangle"), opts.min_stretch and "min_stretch" or "the simplifier's default min_stretch",
      num(threshold), q.stretch_min)
  end
  if js then
    local cap = opts.display_triangles
    if cap == nil then cap = DEFAULT_DISPLAY_TRIANGLES end
    local big = cap and q.triangles > cap
    local display <close> = big and display_copy(mesh, cap) or nil
    local glb, note
    if big then
      -- Above cap triangles: a copy simplified for display (as far as the
      -- simplifier gets towards cap), in the compact GLB.
      local shown = display or mesh
      local _, _, st = element_measures(shown)
      glb = glb_compact(shown, st)
      local nshown = shown:counts().triangles
      note = format("The 3D view shows %s, so that the page stays small; each vertex is coloured by the least "
        .. "stretch of the triangles around it. The table and the charts are the full mesh's.",
        display and format("a copy simplified for display with femlod.simplify: %d of the mesh's %d triangles",
          nshown, q.triangles) or format("the mesh's %d triangles", q.triangles))
      summary.display_triangles = nshown
    else
      local ok, g = pcall(mesh.encode, mesh, name .. ".glb", { color_by = "stretch" })
      if not ok then error(format("%s: cannot make the GLB: %s", opts.html, tostring(g)), 2) end
      glb = g
    end
    parts[#parts + 1] = '<div class="view">'
    parts[#parts + 1] = '<model-viewer id="viewer" alt="' .. esc(name) .. ' coloured by stretch" '
      .. 'camera-controls interaction-prompt="none" shadow-intensity="0" exposure="1" '
      .. 'src="data:model/gltf-binary;base64,' .. base64(glb) .. '"></model-viewer>'
    local stops = {}
    for i, c in ipairs(VIRIDIS) do
      stops[i] = format('<stop offset="%d%%" stop-color="%s"/>', (i - 1) * 25, c)
    end
    parts[#parts + 1] = '<div class="legend"><span>stretch 0</span><svg id="legend" width="200" height="14" '
      .. 'xmlns="http://www.w3.org/2000/svg"><defs><linearGradient id="viridis">' .. concat(stops)
      .. '</linearGradient></defs><rect width="200" height="14" fill="url(#viridis)"/></svg><span>1</span>'
      .. format('<span class="note">(per %s; drag to turn, scroll to zoom)</span></div>', note and "vertex" or "triangle")
    if note then
      parts[#parts + 1] = '<p class="note" id="display-note">' .. esc(note) .. "</p>"
    end
    parts[#parts + 1] = "</div>"
    summary.viewer = true
  else
    side[#side + 1] = '<p class="note">3D view left out (viewer = false).</p>'
  end
  side[#side + 1] = "</div>"
  parts[#parts + 1] = concat(side, "\n")
  parts[#parts + 1] = "</div>"
  parts[#parts + 1] = "<h2>Distributions</h2>"
  parts[#parts + 1] = '<div class="charts">'
  parts[#parts + 1] = stretch_chart
  parts[#parts + 1] = size_chart
  parts[#parts + 1] = valence_chart
  parts[#parts + 1] = "</div>"
  if js then
    -- An inline module: "</script" cannot occur in it, so escape it where it would.
    parts[#parts + 1] = '<script type="module">\n' .. gsub(js, "</(script)", "<\\/%1") .. "\n</script>"
  end
  parts[#parts + 1] = "</body>\n</html>\n"
  write_atomic(opts.html, concat(parts, "\n"), 3)
  summary.html = opts.html
  return summary
end

-- sweep_page(manifest, path): the page comparing all points of a sweep
-- (the manifest as a Lua table): a table of the points, element count
-- against stretch and against deviation.
function M.sweep_page(man, path)
  if type(man) ~= "table" or type(man.points) ~= "table" then
    error(format("bad argument #1 to 'sweep_page' (manifest table expected, got %s)", type(man)), 2)
  end
  if type(path) ~= "string" then
    error(format("bad argument #2 to 'sweep_page' (string expected, got %s)", type(path)), 2)
  end
  local names = {}
  for i, a in ipairs(man.grid or {}) do names[i] = a.name end
  local function last_mesh(p)
    local ms = p.meshes or {}
    return ms[#ms]
  end
  local function label(p)
    local l = {}
    for i, n in ipairs(names) do l[i] = n .. "=" .. tostring((p.params or {})[n]) end
    return format("point %03d %s", p.index or 0, concat(l, " "))
  end
  local rows = { '<table id="points"><tr><th>point</th><th class="name">status</th>' }
  for _, n in ipairs(names) do rows[1] = rows[1] .. "<th>" .. esc(n) .. "</th>" end
  rows[1] = rows[1] .. "<th class=\"name\">mesh</th><th>elements</th><th>stretch avg</th><th>stretch min</th>"
    .. "<th>size max</th><th>valence max</th><th>deviation (rel.)</th><th class=\"name\">error</th></tr>"
  -- Series: the values of the second grid axis, in the grid's order.
  local series_name = names[2]
  local series_values, series_of = nil, {}
  if series_name then
    series_values = {}
    for i, v in ipairs(man.grid[2].values or {}) do
      series_values[i] = v
      series_of[tostring(v)] = i
    end
  end
  local s_avg, s_min, dev = {}, {}, {}
  local nok, nmesh = 0, 0
  for _, p in ipairs(man.points) do
    local m = last_mesh(p)
    if p.status == "ok" then nok = nok + 1 end
    local cells = { format("<td>%03d</td>", p.index or 0), format('<td class="name%s">%s</td>',
      p.status == "ok" and "" or " failed", esc(p.status or "?")) }
    for _, n in ipairs(names) do cells[#cells + 1] = "<td>" .. esc(tostring((p.params or {})[n])) .. "</td>" end
    local function cell(v, fmt)
      return "<td>" .. (type(v) == "number" and format(fmt, v) or "") .. "</td>"
    end
    cells[#cells + 1] = "<td class=\"name\">" .. esc(m and m.path or "") .. "</td>"
    cells[#cells + 1] = cell(m and m.triangles, "%d")
    cells[#cells + 1] = cell(m and m.stretch_avg, "%.3f")
    cells[#cells + 1] = cell(m and m.stretch_min, "%.3f")
    cells[#cells + 1] = cell(m and m.size_max, "%.4g")
    cells[#cells + 1] = cell(m and m.valence_max, "%d")
    cells[#cells + 1] = cell(m and m.hausdorff_rel, "%.4g")
    cells[#cells + 1] = "<td class=\"name\">" .. esc(type(p.error) == "string" and p.error or "") .. "</td>"
    rows[#rows + 1] = "<tr>" .. concat(cells) .. "</tr>"
    if m and type(m.triangles) == "number" then
      nmesh = nmesh + 1
      local l, short = label(p), format("%03d", p.index or 0)
      local sv = series_name and series_of[tostring((p.params or {})[series_name])] or nil
      s_avg[#s_avg + 1] = { m.triangles, m.stretch_avg, l, short, sv }
      s_min[#s_min + 1] = { m.triangles, m.stretch_min, l, short, sv }
      if type(m.hausdorff_rel) == "number" then dev[#dev + 1] = { m.triangles, m.hausdorff_rel, l, short, sv } end
    end
  end
  rows[#rows + 1] = "</table>"
  local npoints = #man.points
  local title = "femlod sweep: " .. tostring(man.recipe and man.recipe.path or "recipe")
  local parts = { page_head(title), "<h1>" .. esc(title) .. "</h1>",
    format('<p class="note" id="counts">%s: %d ok, %d failed; digest %s; %s</p>', plural(npoints, "point"), nok,
      npoints - nok, esc(man.digest or "?"), esc(man.femlod or "femlod")) }
  if nmesh == 0 then
    -- Nothing to compare: say so plainly instead of empty charts.
    local lead = npoints == 0 and "The sweep has no points."
      or nok == 0 and (npoints == 1 and "The point failed." or format("All %d points failed.", npoints))
    parts[#parts + 1] = format('<p class="failed" id="no-results">%sNo point saved a mesh, so there is '
      .. 'nothing to plot.%s</p>', lead and "<b>" .. esc(lead) .. "</b> " or "",
      npoints > nok and " Each failed point\'s reason is in the error column below, in results.csv and in the "
        .. "point\'s stderr.txt." or "")
    parts[#parts + 1] = "<h2>Points</h2>"
    parts[#parts + 1] = concat(rows, "\n")
  else
    parts[#parts + 1] = "<h2>Elements against quality</h2>"
    if series_values then
      local items = {}
      for i, v in ipairs(series_values) do
        items[i] = format('<span class="item"><span class="swatch" style="background:%s"></span>%s = %s</span>',
          SERIES[(i - 1) % #SERIES + 1], esc(series_name), esc(tostring(v)))
      end
      parts[#parts + 1] = '<div class="series-legend" id="series-legend">' .. concat(items) .. "</div>"
    end
    local snames = series_values and series_values or nil
    parts[#parts + 1] = '<div class="charts">'
    parts[#parts + 1] = scatter("sweep-stretch-avg", "Average stretch", s_avg, "elements", "stretch (avg)", snames)
    parts[#parts + 1] = scatter("sweep-stretch-min", "Minimum stretch", s_min, "elements", "stretch (min)", snames)
    parts[#parts + 1] = scatter("sweep-deviation", "Deviation from the input", dev, "elements",
      "Hausdorff / diagonal", snames)
    parts[#parts + 1] = "</div>"
    parts[#parts + 1] = "<h2>Points</h2>"
    parts[#parts + 1] = concat(rows, "\n")
  end
  parts[#parts + 1] = "</body>\n</html>\n"
  write_atomic(path, concat(parts, "\n"), 3)
  return path
end

-- }======

return M
