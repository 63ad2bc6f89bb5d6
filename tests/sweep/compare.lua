-- compare.lua: a sweep run in one go (`femlod sweep ... --out DIRECT`) against
-- the same sweep run as --emit-jobs commands by an engine (GNU parallel, a
-- Slurm job array) and then --collect (`--out JOBS`). Run by
-- tests/sweep/engines.sh:
--
--   femlod run compare.lua direct=DIRECT jobs=JOBS points=N engine=NAME
--
-- What must be identical, and is checked so:
--   manifest.json   the digest, and the whole text but the `runs` member
--                   (wall, user and system seconds and peak memory of each
--                   worker: the only part that changes between runs)
--   results.csv     every column but `seconds` and `max_rss_kb` (the same
--                   two figures), every point `ok`
--   report.html     byte for byte
--   points/NNN/     the same files; each byte for byte, but record.json with
--                   the sweep's folder written as DIR (the worker gets its
--                   out_dir as an absolute path, DIRECT/points/NNN or
--                   JOBS/points/NNN, and records the paths it wrote as the
--                   recipe spelled them: the manifest makes them relative)
--                   and run.json, whose timings differ (its exit and signal
--                   must not)

local T = dofile((arg[0]:match("^(.*)/") or ".") .. "/../lua/check.lua")

local P = params
assert(P and P.direct and P.jobs and P.points and P.engine, "needs direct=, jobs=, points=, engine=")
local direct, jobs, npoints = tostring(P.direct), tostring(P.jobs), math.tointeger(P.points)

local function read(dir, name)
  return T.readfile(dir .. "/" .. name)
end

-- {====== manifest.json
local md, mj = read(direct, "manifest.json"), read(jobs, "manifest.json")
T.check(md, direct .. "/manifest.json written by the sweep")
T.check(mj, jobs .. "/manifest.json written by --collect")
md, mj = md or "", mj or ""
local dd, dj = md:match('"digest":%s*"(%x+)"'), mj:match('"digest":%s*"(%x+)"')
T.check(dd and #dd == 64, "a SHA-256 digest in the sweep's manifest")
T.eq(dj, dd, P.engine .. " + --collect: the digest of the sweep run in one go")
-- Everything before "runs" (format, version, digest, femlod, recipe, seed,
-- grid, fixed, points), text for text.
local function before_runs(m) return m:match('^(.-)\n%s*"runs":') end
local hd, hj = before_runs(md), before_runs(mj)
T.check(hd and hj, "both manifests have a runs member")
T.eq(hj, hd, "manifest.json identical but for runs")
local function runs(m)
  local list = {}
  for s in (m:match('"runs":(.*)$') or ""):gmatch('"seconds":%s*([%d.e+-]+)') do list[#list + 1] = tonumber(s) end
  return list
end
local rd, rj = runs(md), runs(mj)
T.eq(#rj, npoints, "runs: one entry per point, with its time")
for i, s in ipairs(rj) do T.check(s > 0, "point " .. (i - 1) .. " ran for some time: " .. s) end
T.eq(#rd, npoints, "the direct sweep's runs")
-- }======

-- {====== results.csv
local VARY = { seconds = true, max_rss_kb = true }
local rows_d, head_d = T.read_csv(direct .. "/results.csv")
local rows_j, head_j = T.read_csv(jobs .. "/results.csv")
T.eq(table.concat(head_j, ","), table.concat(head_d, ","), "results.csv: the same columns")
T.eq(#rows_j, npoints, "results.csv: one row per point")
T.eq(#rows_d, npoints, "results.csv of the direct sweep")
for i, r in ipairs(rows_d) do
  local rj_ = rows_j[i] or {}
  T.eq(rj_.status, "ok", "point " .. (i - 1) .. " ok through " .. P.engine)
  for _, k in ipairs(head_d) do
    if not VARY[k] then T.eq(rj_[k], r[k], "results.csv point " .. (i - 1) .. " column " .. k) end
  end
end
-- }======

T.eq(read(jobs, "report.html"), read(direct, "report.html"), "report.html byte for byte")

-- {====== the points' folders
local function list(dir)
  local p = assert(io.popen("ls -A " .. T.quote(dir)))
  local names = {}
  for l in p:lines() do names[#names + 1] = l end
  p:close()
  return names
end
local function plain(s) return (s:gsub("%p", "%%%0")) end
local pts = list(direct .. "/points")
T.eq(#pts, npoints, "one folder per point")
T.eq(table.concat(list(jobs .. "/points"), " "), table.concat(pts, " "), "the same point folders")
for _, pt in ipairs(pts) do
  local fd, fj = direct .. "/points/" .. pt, jobs .. "/points/" .. pt
  local names = list(fd)
  T.eq(table.concat(list(fj), " "), table.concat(names, " "), "points/" .. pt .. ": the same files")
  for _, name in ipairs(names) do
    local a, b = T.readfile(fd .. "/" .. name), T.readfile(fj .. "/" .. name) or ""
    local what = "points/" .. pt .. "/" .. name
    if name == "record.json" then
      a, b = a:gsub(plain(direct), "DIR"), b:gsub(plain(jobs), "DIR")
      T.check(a:find('"out_dir":%s*"DIR/points/' .. pt .. '"'), what .. ": out_dir is the point's folder")
      T.eq(b, a, what .. " identical but for the sweep's folder")
    elseif name == "run.json" then
      for _, k in ipairs { "exit", "signal" } do
        local pat = '"' .. k .. '":%s*([^,\n]+)'
        T.eq(b:match(pat), a:match(pat), what .. ": " .. k)
      end
      T.eq(b:match('"exit":%s*(%d+)'), "0", what .. ": exit 0")
    else
      T.eq(b, a, what .. " byte for byte")
    end
  end
end
-- }======

print(string.format("%s: %d points, digest %s; manifests equal but for runs, results.csv but for "
  .. "seconds and max_rss_kb, every point's files but for record.json's folder and run.json's timings",
  P.engine, npoints, dd or "?"))
T.summary("compare_" .. P.engine)
