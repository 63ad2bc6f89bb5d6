-- test_progress.lua: femlod.progress (the bar's text, throttling, close,
-- options) and the bar of `femlod simplify` on a terminal (script(1)) and
-- its absence elsewhere.

local T = dofile((arg[0]:match("^(.*)/") or ".") .. "/check.lua")
local femlod = require "femlod"
local progress = require "femlod.progress"

local P = params
assert(P and P.femlod and P.tmp and P.shared, "run through ctest: needs femlod=, tmp=, shared=")
local quote = T.quote

-- A stream that keeps what is written.
local function sink()
  local s = { text = "", flushes = 0 }
  function s:write(x) self.text = self.text .. x return self end
  function s:flush() self.flushes = self.flushes + 1 return true end
  return s
end

do
  local out = sink()
  local bar = progress.bar { label = "work", stream = out, force = true }
  T.eq(type(bar.update), "function", "bar.update is the progress function")
  T.eq(bar.update(0.5), nil, "update returns nothing: never stops the work")
  T.check(out.text:find("^\r\27%[Kwork %[############............%]  50%%  [%d.]+ s  [%d?]+ %%/s  ETA "),
    "bar text: " .. T.show(out.text))
  local n = #out.text
  bar.update(0.51)
  T.eq(#out.text, n, "redraws at most 10 times a second")
  bar.update(1)
  T.check(out.text:find("%[########################%] 100%%", n + 1), "done is always drawn")
  bar:close()
  T.check(out.text:find("\r\27%[K$"), "close clears the line")
  local m = #out.text
  bar.update(0.7)
  bar:close()
  T.eq(#out.text, m, "a closed bar draws nothing")
  local quiet = sink()
  do
    local b <close> = progress.bar { stream = quiet }
    b.update(0.3)
  end
  T.eq(quiet.text, "", "a given stream without force: no bar")
  T.eq(progress.enabled(), false, "ctest's stderr is not a terminal")
  local clamp = sink()
  local c = progress.bar { stream = clamp, force = true }
  c.update(7)
  T.check(clamp.text:find("100%%"), "done above 1 is 1")
  T.checkerr("unknown option 'lable'; valid: force, label, stream", progress.bar, { lable = "x" })
  T.checkerr("label: string expected, got number", progress.bar, { label = 1 })
  T.checkerr("table expected, got string", progress.bar, "x")
  T.checkerr("0, 1 or 2 expected", femlod._isatty, 7)
end

-- With simplify, as the CLI uses it: the result is the same as without.
do
  local m <close> = femlod.load(P.shared .. "/fandisk.obj")
  local out = sink()
  local bar <close> = progress.bar { label = "simplify", stream = out, force = true }
  local h1 <close> = m:simplify { target = 3000, progress = bar.update }
  local h2 <close> = m:simplify { target = 3000 }
  T.check(out.text:find("simplify %[#+%.*%]"), "the bar moved")
  T.eq(h1:mesh():quality().stretch_avg, h2:mesh():quality().stretch_avg, "the bar changes nothing")
  T.eq(h1:stats().stop_reason, "target", "not cancelled")
end

-- femlod simplify: a bar on a terminal, none in a pipe or with --quiet.
do
  local out_mesh = P.tmp .. "/progress_fan.obj"
  local line = quote(P.femlod) .. " simplify " .. quote(P.shared .. "/fandisk.obj") .. " " .. quote(out_mesh)
    .. " --target 3000"
  local p = io.popen("script -qec " .. quote(line) .. " /dev/null </dev/null")
  local tty = p:read("a")
  T.check(p:close(), "simplify under a terminal")
  T.check(tty:find("\27%[Ksimplify %[#+%.*%] +%d+%%"), "bar on the terminal")
  T.check(tty:find("\r\27%[Kmodel %(H x W x D%)"), "cleared before the report")
  p = io.popen(line .. " 2>&1 </dev/null")
  local piped = p:read("a")
  p:close()
  T.check(not piped:find("simplify %["), "no bar in a pipe")
  T.check(piped:find("^model %(H x W x D%)"), "report first")
  p = io.popen("script -qec " .. quote(quote(P.femlod) .. " -q simplify " .. quote(P.shared .. "/fandisk.obj") .. " "
    .. quote(out_mesh) .. " --target 3000") .. " /dev/null </dev/null")
  local q = p:read("a")
  p:close()
  T.eq(q, "", "--quiet: nothing, not even the bar")
  os.remove(out_mesh)
end

T.summary("test_progress")
