-- femlod.report: quality tables (mesh:quality()) as text.
--
--   local report = require "femlod.report"
--   print(report.text(mesh:quality(), "part.obj"))    -- multi-line report with histogram
--   print(report.header()); print(report.row(q, "part.obj", "original"))  -- a Table 1 row
--   print(report.fields(q))                            -- "key value" lines, sorted
--   print(report.stats(h:stats()))                     -- how a simplification went
--   local r = report.report(mesh, { reference = m0, html = "part.html" })  -- also femlod.report
--   report.sweep_page(manifest, "sweep.html")          -- what `femlod sweep` writes
--
-- Each function also takes a femlod.Mesh instead of its quality table
-- (report.stats a femlod.Hierarchy instead of its stats table).
-- The text functions are pure Lua over the quality table's fields; report()
-- and sweep_page() build HTML pages (html.lua's part below).

local type, error, pairs, ipairs, tostring, getmetatable = type, error, pairs, ipairs, tostring, getmetatable
local pcall = pcall
local format, rep, concat, sort = string.format, string.rep, table.concat, table.sort
local byte, sub, gsub = string.byte, string.sub, string.gsub
local floor, max, min, sqrt, abs, huge = math.floor, math.max, math.min, math.sqrt, math.abs, math.huge
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
-- deviation above it is flagged.
function M.text(q, name, max_deviation)
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

-- Four lines: why and after how much work it stopped, which checks refused
-- collapses (counts of edge evaluations), the input triangles left breaking
-- a threshold, and the thresholds in force ("off" when switched off, target
-- "none" when there was none).
function M.stats(s)
  s = stats_of(s, "stats")
  local rej, th = {}, {}
  for i, k in ipairs(REJECTED) do rej[i] = format("%s %d", k, s.rejected[k] or 0) end
  for i, k in ipairs(THRESHOLDS) do
    local v = s.thresholds[k]
    local off = k == "target" and "none" or "off"
    th[i] = format("%s %s", k, v == false and off or type(v) == "number" and num(v) or "?")
  end
  return concat({
    format("stop: %s; %s (%d in the pre-phase%s) in %.3f s", s.stop_reason,
      plural(s.collapses, "collapse"), s.prephase_collapses,
      (s.fast_collapses or 0) > 0 and format(", %d in fast passes on %s", s.fast_collapses,
        plural(s.threads or 1, "thread")) or "",
      s.seconds),
    "rejected: " .. concat(rej, ", "),
    format("violating input: %s; dropped degenerate: %d", plural(s.violating_input, "triangle"),
      s.dropped_degenerate),
    "thresholds: " .. concat(th, ", "),
  }, "\n")
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

-- A bar chart: bars {label, count}, labelled under each bar, or, with
-- edges (n + 1 strings), at the bin edges; returns the <svg> element.
local function bar_chart(id, title, bars, xlabel, edges)
  local W, H, L, R, T, Bm = 420, 240, 56, 12, 28, 46
  local most = 0
  for _, b in ipairs(bars) do most = max(most, b[2]) end
  local out = { format('<svg id="%s" class="chart" xmlns="http://www.w3.org/2000/svg" viewBox="0 0 %d %d" '
    .. 'width="%d" height="%d" role="img" aria-label="%s">', id, W, H, W, H, esc(title)) }
  out[#out + 1] = format('<text x="%d" y="18" class="title">%s</text>', W // 2, esc(title))
  local pw, ph = W - L - R, H - T - Bm
  out[#out + 1] = format('<line x1="%d" y1="%d" x2="%d" y2="%d" class="axis"/>', L, T + ph, L + pw, T + ph)
  out[#out + 1] = format('<line x1="%d" y1="%d" x2="%d" y2="%d" class="axis"/>', L, T, L, T + ph)
  for k = 0, 4 do
    local v = most * k / 4
    local y = T + ph - ph * k / 4
    out[#out + 1] = format('<text x="%d" y="%s" class="tick" text-anchor="end">%s</text>', L - 4, c2(y + 4),
      most >= 4 and format("%d", floor(v + 0.5)) or num(v))
  end
  local n = #bars
  local bw = n > 0 and pw / n or pw
  local every = n > 12 and floor(n / 10 + 0.5) or 1
  for i, b in ipairs(bars) do
    local h = most > 0 and ph * b[2] / most or 0
    local x = L + (i - 1) * bw
    out[#out + 1] = format('<rect class="bar" x="%s" y="%s" width="%s" height="%s"><title>%s: %d</title></rect>',
      c2(x + 1), c2(T + ph - h), c2(max(bw - 2, 1)), c2(h), esc(b[1]), b[2])
    if not edges and (i - 1) % every == 0 then
      out[#out + 1] = format('<text x="%s" y="%d" class="tick" text-anchor="middle">%s</text>', c2(x + bw / 2),
        T + ph + 14, esc(b[1]))
    end
  end
  if edges then
    local step = n > 5 and 2 or 1
    for k = 0, n, step do
      out[#out + 1] = format('<text x="%s" y="%d" class="tick" text-anchor="middle">%s</text>', c2(L + k * bw),
        T + ph + 14, esc(edges[k + 1]))
    end
  end
  out[#out + 1] = format('<text x="%d" y="%d" class="label" text-anchor="middle">%s</text>', L + pw // 2, H - 8,
    esc(xlabel))
  out[#out + 1] = "</svg>"
  return concat(out, "\n")
end

-- A scatter plot: points {x, y, label}; returns the <svg> element.
local function scatter(id, title, pts, xlabel, ylabel)
  local W, H, L, R, T, Bm = 420, 260, 70, 16, 28, 46
  local xmin, xmax, ymin, ymax = huge, -huge, huge, -huge
  local shown = {}
  for _, p in ipairs(pts) do
    if type(p[1]) == "number" and type(p[2]) == "number" then
      shown[#shown + 1] = p
      xmin, xmax = min(xmin, p[1]), max(xmax, p[1])
      ymin, ymax = min(ymin, p[2]), max(ymax, p[2])
    end
  end
  if #shown == 0 then xmin, xmax, ymin, ymax = 0, 1, 0, 1 end
  if xmax == xmin then xmin, xmax = xmin - 1, xmax + 1 end
  if ymax == ymin then
    local d = ymin ~= 0 and abs(ymin) * 0.1 or 1
    ymin, ymax = ymin - d, ymax + d
  end
  local dx, dy = (xmax - xmin) * 0.06, (ymax - ymin) * 0.08
  xmin, xmax, ymin, ymax = xmin - dx, xmax + dx, ymin - dy, ymax + dy
  local pw, ph = W - L - R, H - T - Bm
  local function X(x) return L + pw * (x - xmin) / (xmax - xmin) end
  local function Y(y) return T + ph - ph * (y - ymin) / (ymax - ymin) end
  local out = { format('<svg id="%s" class="chart" xmlns="http://www.w3.org/2000/svg" viewBox="0 0 %d %d" '
    .. 'width="%d" height="%d" role="img" aria-label="%s">', id, W, H, W, H, esc(title)) }
  out[#out + 1] = format('<text x="%d" y="18" class="title">%s</text>', W // 2, esc(title))
  out[#out + 1] = format('<line x1="%d" y1="%d" x2="%d" y2="%d" class="axis"/>', L, T + ph, L + pw, T + ph)
  out[#out + 1] = format('<line x1="%d" y1="%d" x2="%d" y2="%d" class="axis"/>', L, T, L, T + ph)
  for k = 0, 4 do
    local xv, yv = xmin + (xmax - xmin) * k / 4, ymin + (ymax - ymin) * k / 4
    out[#out + 1] = format('<text x="%s" y="%d" class="tick" text-anchor="middle">%s</text>', c2(X(xv)),
      T + ph + 14, format("%.4g", xv))
    out[#out + 1] = format('<text x="%d" y="%s" class="tick" text-anchor="end">%s</text>', L - 4, c2(Y(yv) + 4),
      format("%.4g", yv))
  end
  for _, p in ipairs(shown) do
    out[#out + 1] = format('<circle class="dot" cx="%s" cy="%s" r="5"><title>%s</title></circle>', c2(X(p[1])),
      c2(Y(p[2])), esc(p[3] or ""))
    if p[4] then
      out[#out + 1] = format('<text x="%s" y="%s" class="dotlabel">%s</text>', c2(X(p[1]) + 7), c2(Y(p[2]) - 6),
        esc(p[4]))
    end
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
#viewer { width: 640px; height: 480px; background: #f0f0f0; border: 1px solid #ddd; }
.legend { display: flex; align-items: center; gap: 8px; font-size: 12px; }
.note { color: #666; font-size: 12px; }
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

-- Per-triangle size (longest edge) and per-vertex valence (distinct
-- neighbours through edges), as the quality report defines them.
local function element_measures(mesh)
  local P, Tr = mesh:positions(), mesh:triangles()
  local sizes, nb = {}, {}
  local function d(a, b)
    local x, y, z = a[1] - b[1], a[2] - b[2], a[3] - b[3]
    return sqrt(x * x + y * y + z * z)
  end
  local edges = {}
  local nv = #P
  for i, t in ipairs(Tr) do
    local a, b, c = P[t[1]], P[t[2]], P[t[3]]
    sizes[i] = max(d(a, b), d(b, c), d(c, a))
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
  return sizes, nb
end

local function size_bars(sizes, smax)
  local bins, counts = 10, {}
  for k = 1, bins do counts[k] = 0 end
  for _, s in ipairs(sizes) do
    local k = smax > 0 and floor(s / smax * bins) + 1 or 1
    if k > bins then k = bins end
    counts[k] = counts[k] + 1
  end
  local bars, edges = {}, {}
  for k = 1, bins do
    bars[k] = { format("[%.3g, %.3g%s", smax * (k - 1) / bins, smax * k / bins, k == bins and "]" or ")"),
      counts[k] }
  end
  for k = 0, bins do edges[k + 1] = format("%.3g", smax * k / bins) end
  return bars, counts, edges
end

local function valence_bars(nb)
  local counts, lo, hi = {}, huge, -huge
  for _, v in pairs(nb) do
    counts[v] = (counts[v] or 0) + 1
    lo, hi = min(lo, v), max(hi, v)
  end
  local bars, list = {}, {}
  if lo > hi then return bars, list end
  for v = lo, hi do
    bars[#bars + 1] = { format("%d", v), counts[v] or 0 }
    list[#list + 1] = { valence = v, count = counts[v] or 0 }
  end
  return bars, list
end

local REPORT_KEYS = { reference = true, html = true, name = true, reference_name = true, viewer = true,
  title = true, progress = true, max_deviation = true }

local function check_opts(opts)
  if opts == nil then return {} end
  if type(opts) ~= "table" then
    error(format("bad argument #2 to 'report' (table expected, got %s)", type(opts)), 3)
  end
  for k in pairs(opts) do
    if not REPORT_KEYS[k] then
      error(format("bad argument #2 to 'report' (unknown option '%s'; valid: html, max_deviation, name, "
        .. "progress, reference, reference_name, title, viewer)", tostring(k)), 3)
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
  if opts.max_deviation ~= nil and not (type(opts.max_deviation) == "number" and opts.max_deviation > 0) then
    error(format("bad argument #2 to 'report' (max_deviation: positive number expected, got %s)",
      tostring(opts.max_deviation)), 3)
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
  local sizes, nb = element_measures(mesh)
  local sbars, sedges = {}, {}
  local nbins = #q.histogram
  for k, n in ipairs(q.histogram) do
    sbars[k] = { format("[%.1f, %.1f%s", (k - 1) / nbins, k / nbins, k == nbins and "]" or ")"), n }
  end
  for k = 0, nbins do sedges[k + 1] = format("%.1f", k / nbins) end
  local zbars, zcounts, zedges = size_bars(sizes, q.size_max)
  local vbars, vlist = valence_bars(nb)
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
    text = M.text(q, name, opts.max_deviation),
    deviation_exceeded = q.hausdorff ~= nil and opts.max_deviation ~= nil and q.hausdorff > opts.max_deviation,
    histograms = { stretch = q.histogram, size = zcounts, size_max = q.size_max, valence = vlist },
    hausdorff = q.hausdorff, hausdorff_rel = q.hausdorff_rel,
    viewer = false,
  }
  if not opts.html then return summary end

  local js
  if opts.viewer ~= false then js = find_viewer(opts.viewer) end
  local title = opts.title or ("femlod report: " .. name)
  local parts = { page_head(title), "<h1>" .. esc(title) .. "</h1>",
    format('<p class="note">%s; written by femlod</p>', esc(M.text(q, name):match("^[^\n]*"))),
    "<h2>Quality (the paper's Table 1 columns)</h2>", table1(rows) }
  if ref then
    parts[#parts + 1] = format('<p id="deviation">Hausdorff deviation from the reference: <b>%s</b> '
      .. '(%s of the reference\'s bounding-box diagonal; forward %s, backward %s)</p>', num(q.hausdorff),
      num(q.hausdorff_rel), num(q.hausdorff_forward), num(q.hausdorff_backward))
    if summary.deviation_exceeded then
      parts[#parts + 1] = format('<p id="deviation-exceeded"><b>The deviation exceeds max_deviation %s.</b></p>',
        num(opts.max_deviation))
    end
  end
  parts[#parts + 1] = "<h2>Distributions</h2>"
  parts[#parts + 1] = '<div class="charts">'
  parts[#parts + 1] = bar_chart("stretch-histogram", "Stretch distribution (triangles)", sbars, "stretch", sedges)
  parts[#parts + 1] = bar_chart("size-histogram", "Size distribution (triangles)", zbars, "longest edge", zedges)
  parts[#parts + 1] = bar_chart("valence-histogram", "Valence distribution (vertices)", vbars, "valence")
  parts[#parts + 1] = "</div>"
  if js then
    local ok, glb = pcall(mesh.encode, mesh, name .. ".glb", { color_by = "stretch" })
    if not ok then error(format("%s: cannot make the GLB: %s", opts.html, tostring(glb)), 2) end
    parts[#parts + 1] = "<h2>Stretch on the mesh</h2>"
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
      .. '<span class="note">(per triangle; drag to turn, scroll to zoom)</span></div>'
    -- An inline module: "</script" cannot occur in it, so escape it where it would.
    parts[#parts + 1] = '<script type="module">\n' .. gsub(js, "</(script)", "<\\/%1") .. "\n</script>"
    summary.viewer = true
  else
    parts[#parts + 1] = '<p class="note">3D view left out (viewer = false).</p>'
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
  local s_avg, s_min, dev = {}, {}, {}
  for _, p in ipairs(man.points) do
    local m = last_mesh(p)
    local cells = { format("<td>%03d</td>", p.index or 0), "<td class=\"name\">" .. esc(p.status or "?") .. "</td>" }
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
      local l, short = label(p), format("%03d", p.index or 0)
      s_avg[#s_avg + 1] = { m.triangles, m.stretch_avg, l, short }
      s_min[#s_min + 1] = { m.triangles, m.stretch_min, l, short }
      if type(m.hausdorff_rel) == "number" then dev[#dev + 1] = { m.triangles, m.hausdorff_rel, l, short } end
    end
  end
  rows[#rows + 1] = "</table>"
  local title = "femlod sweep: " .. tostring(man.recipe and man.recipe.path or "recipe")
  local parts = { page_head(title), "<h1>" .. esc(title) .. "</h1>",
    format('<p class="note">%d points; digest %s; %s</p>', #man.points, esc(man.digest or "?"),
      esc(man.femlod or "femlod")),
    "<h2>Points</h2>", concat(rows, "\n"), "<h2>Elements against quality</h2>", '<div class="charts">',
    scatter("sweep-stretch-avg", "Average stretch", s_avg, "elements", "stretch (avg)"),
    scatter("sweep-stretch-min", "Minimum stretch", s_min, "elements", "stretch (min)"),
    scatter("sweep-deviation", "Deviation from the input", dev, "elements", "Hausdorff / diagonal"),
    "</div>", "</body>\n</html>\n" }
  write_atomic(path, concat(parts, "\n"), 3)
  return path
end

-- }======

return M
