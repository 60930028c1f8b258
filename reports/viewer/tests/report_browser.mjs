// The report in a real browser: a short real run (physbench) becomes a report (build_report.py),
// which headless Chromium opens from file://. Any page: no JavaScript error, no console error, no
// failed request. The replay viewer: every replay started; two engines' viewports draw bodies
// (coloured pixels read back from the canvas); the decoded poses match the scene file; moving the
// slider changes each engine's picture; on the tower, the contact points toggle on and off (their
// dark rings appear and go) and colouring by penetration paints each body by its own depth. The
// full results table: linked from the front page, scrolling sideways in its own box, not the
// page; a click on a number column's header puts its least value first, a second click its
// largest, empty cells last both times; a click on a text column's header orders the rows by it;
// the text, engine and status filters show exactly the rows that match.
// The first screen, in a window 1,400 pixels wide: each of its small charts drew (an svg with a
// trace's path or point), and no chart's legend or title overlaps another chart, a heading, a
// question or a table; its screenshot (the top 1,400 x 1,000 pixels) goes to PHYSBENCH_ARTIFACTS,
// and with PHYSBENCH_SCREENSHOT_DOCS=1 also to docs/report-first-screen.png, which the README shows
// (made from a full run's folder; a test run leaves the repository's copy alone).
// Screenshots go to PHYSBENCH_ARTIFACTS (viewer.png, viewer-tumbling-box.png, viewer-contacts.png,
// report-first-screen.png).
//
//   node reports/viewer/tests/report_browser.mjs            (CTest sets the environment)
//   node reports/viewer/tests/report_browser.mjs PAGE.html  (the page checks on any built report)
//   node reports/viewer/tests/report_browser.mjs RESULTS/   (report that run's folder, every check)
//
// Exit 77 (CTest's skip) only when Chromium is absent.
import { execFileSync } from 'node:child_process';
import { existsSync, mkdirSync, mkdtempSync, readFileSync, rmSync, statSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { dirname, join, resolve } from 'node:path';
import { fileURLToPath, pathToFileURL } from 'node:url';
import { chromium } from 'playwright-core';

const here = dirname(fileURLToPath(import.meta.url));
const root = resolve(here, '../../..');
const browserPath = process.env.PHYSBENCH_CHROMIUM || '/usr/bin/chromium';
const artifacts = process.env.PHYSBENCH_ARTIFACTS || join(root, 'build', 'artifacts');

let failures = 0;
function check(ok, what) {
  console.log(`${ok ? 'ok  ' : 'FAIL'} ${what}`);
  if (!ok) failures++;
}

// ---- any page: load it, collect every error ------------------------------------------------

export async function openReport(browser, page_path, viewport = { width: 1280, height: 900 }) {
  const page = await browser.newPage({ viewport });
  const errors = [];
  page.on('pageerror', (e) => errors.push(`page error: ${e.message}`));
  page.on('console', (m) => { if (m.type() === 'error') errors.push(`console error: ${m.text()}`); });
  page.on('requestfailed', (r) => errors.push(`request failed: ${r.url()} (${r.failure()?.errorText})`));
  await page.goto(pathToFileURL(page_path).href, { waitUntil: 'load' });
  // a page with replays is ready when the viewer says so (it decodes its data asynchronously)
  if (await page.locator('.replay[data-replay]').count())
    await page.waitForFunction(() => window.physbenchReplaysReady === true, null, { timeout: 60000 });
  return { page, errors };
}

// ---- the full results table: sorting and filters ------------------------------------------

// each body row's cells as [text, data-sort or null], visible rows only unless all
async function tableRows(page, all = false) {
  return page.evaluate((all) => [...document.querySelectorAll('#results-table tbody tr')]
    .filter((tr) => all || !tr.hidden)
    .map((tr) => ({ engine: tr.dataset.engine, text: tr.textContent.toLowerCase(),
      cells: [...tr.cells].map((td) => [td.textContent, td.getAttribute('data-sort')]) })), all);
}

async function tableChecks(page) {
  const started = Date.now();
  const table = page.locator('#results-table');
  check(await table.count() === 1, 'the page has the full results table');
  if (!await table.count()) return;
  check(await page.locator('#glance a[href="#results"]').count() > 0, 'the front page links to the full table');
  const widths = await page.evaluate(() => {
    const box = document.querySelector('#results-table').parentElement;
    return { box: box.clientWidth, table: box.scrollWidth, page: document.documentElement.scrollWidth, window: window.innerWidth };
  });
  check(widths.page <= widths.window,
    `the table scrolls in its box, not the page (table ${widths.table} px in a ${widths.box} px box, page ${widths.page} px)`);
  check(await page.locator('#results-controls').isVisible(), 'the table\'s filters are shown (its script ran)');
  const headers = await table.locator('thead th').allTextContents();
  const all = await tableRows(page, true);

  // a number column: least value first, then largest, empty cells last both times
  const column = headers.indexOf('steps/s (median)');
  const values = all.map((r) => r.cells[column][1]).filter((v) => v !== null && v !== '').map(Number);
  const [least, largest] = [Math.min(...values), Math.max(...values)];
  const header = table.locator('thead th').nth(column);
  for (const [order, want] of [['ascending', least], ['descending', largest]]) {
    await header.click();
    const rows = await tableRows(page, true);
    const sorted = rows.map((r) => r.cells[column][1]);
    const filled = sorted.filter((v) => v !== '').map(Number);
    const inOrder = filled.every((v, i) => i === 0 || (order === 'ascending' ? v >= filled[i - 1] : v <= filled[i - 1]));
    const emptiesLast = sorted.slice(filled.length).every((v) => v === '');
    check(Number(sorted[0]) === want && inOrder && emptiesLast,
      `steps/s ${order}: first row ${rows[0].cells[column][0]} (want ${want.toPrecision(3)}), in order, empty cells last`);
  }
  // a text column: engine/variant in alphabetical order
  const labels = headers.indexOf('engine/variant');
  await table.locator('thead th').nth(labels).click();
  const byLabel = (await tableRows(page, true)).map((r) => r.cells[labels][0]);
  // as tablesort compares text: lower case, by code unit
  const alphabetical = [...byLabel].sort((a, b) => (a.toLowerCase() < b.toLowerCase() ? -1 : a.toLowerCase() > b.toLowerCase() ? 1 : 0));
  check(byLabel.join('|') === alphabetical.join('|'), `sorting by engine/variant orders the rows (first ${byLabel[0]})`);

  // the text filter, then the engine filter on top of it: exactly the rows that match
  const word = all[0].cells[0][0].toLowerCase();  // a scenario's name
  await page.locator('#results-controls input[type=search]').fill(word);
  let shown = await tableRows(page);
  const matching = all.filter((r) => r.text.includes(word));
  check(shown.length === matching.length && shown.length < all.length && shown.every((r) => r.text.includes(word)),
    `filtering by "${word}" shows its ${matching.length} of ${all.length} rows (${shown.length} shown)`);
  const engine = all[0].engine;
  await page.locator('#results-controls select[name=engine]').selectOption(engine);
  shown = await tableRows(page);
  const both = matching.filter((r) => r.engine === engine);
  check(shown.length === both.length && shown.every((r) => r.engine === engine),
    `and engine ${engine}: ${both.length} rows (${shown.length} shown)`);
  const count = await page.locator('#results-controls .table-count').textContent();
  check(count === `${both.length} of ${all.length} runs shown`, `the count says "${count}"`);
  // cleared, every row is back; then the status filter alone: the rarest status's rows exactly
  await page.locator('#results-controls input[type=search]').fill('');
  await page.locator('#results-controls select[name=engine]').selectOption('');
  const statuses = await page.evaluate(() => [...document.querySelectorAll('#results-table tbody tr')].map((tr) => tr.dataset.status));
  const rarest = [...new Set(statuses)].sort((a, b) => statuses.filter((s) => s === a).length - statuses.filter((s) => s === b).length)[0];
  await page.locator('#results-controls select[name=status]').selectOption(rarest);
  const byStatus = await page.evaluate(() => [...document.querySelectorAll('#results-table tbody tr')].filter((tr) => !tr.hidden).map((tr) => tr.dataset.status));
  const wanted = statuses.filter((s) => s === rarest).length;
  check(byStatus.length === wanted && byStatus.every((s) => s === rarest), `status ${rarest}: ${wanted} rows (${byStatus.length} shown)`);
  await page.locator('#results-controls select[name=status]').selectOption('');
  check((await tableRows(page)).length === all.length, 'clearing the filters shows every row again');
  console.log(`table checks: ${Date.now() - started} ms`);
}

// ---- the first screen: small charts that drew, nothing overlapping ---------------------------

const FIRST_SCREEN = { width: 1400, height: 1000 };

async function firstScreenChecks(browser, pagePath) {
  const { page, errors } = await openReport(browser, pagePath, FIRST_SCREEN);
  // the first screen's charts draw as the page opens, the rest as they come near the window: the
  // checks below need them all
  await page.waitForFunction(() => [...document.querySelectorAll('#first .plotly-graph-div')]
    .every((d) => d.querySelector('svg.main-svg')), null, { timeout: 30000 });
  await page.evaluate(() => window.physbenchDrawCharts());
  const charts = await page.evaluate(() => [...document.querySelectorAll('#first figure.small')].map((f) => ({
    question: f.querySelector('.question')?.textContent ?? '',
    drawn: f.querySelectorAll('.js-plotly-plot svg.main-svg .trace path, .js-plotly-plot svg.main-svg .trace .point').length,
  })));
  check(charts.length > 0, `the first screen has its small charts (${charts.length})`);
  for (const c of charts)
    check(c.drawn > 0 && c.question.endsWith('?'), `first screen "${c.question}": drew ${c.drawn} paths or points`);
  const top = await page.evaluate(() => {
    const first = document.querySelector('#first');
    return first ? first.getBoundingClientRect().top + window.scrollY : Infinity;
  });
  check(top < FIRST_SCREEN.height / 2, `the charts open the page (${Math.round(top)} px from its top)`);
  // every chart's legend and title against every other chart, heading, question and table on the
  // page, by their boxes in the page (a box that contains the chart, or that it contains, is its own)
  const overlaps = await page.evaluate(() => {
    const area = (b) => Math.max(0, b.x1 - b.x0) * Math.max(0, b.y1 - b.y0);
    const cut = (a, b) => ({ x0: Math.max(a.x0, b.x0), y0: Math.max(a.y0, b.y0), x1: Math.min(a.x1, b.x1), y1: Math.min(a.y1, b.y1) });
    const meet = (a, b) => area(cut(a, b));
    const rect = (el) => { const r = el.getBoundingClientRect(); return { x0: r.left + scrollX, y0: r.top + scrollY, x1: r.right + scrollX, y1: r.bottom + scrollY }; };
    // what is seen of an element: its box within every scrolling box around it (the full table
    // scrolls in one)
    const box = (el) => {
      let seen = rect(el);
      for (let up = el.parentElement; up; up = up.parentElement)
        if (up instanceof HTMLElement && getComputedStyle(up).overflow !== 'visible') seen = cut(seen, rect(up));
      return seen;
    };
    const name = (el) => `${el.tagName.toLowerCase()}${el.id ? '#' + el.id : ''} "${el.textContent.trim().slice(0, 40)}"`;
    const plots = [...document.querySelectorAll('.js-plotly-plot')];
    const others = [...plots, ...document.querySelectorAll('h1, h2, h3, p.question, table, figcaption')];
    const found = [];
    for (const plot of plots) {
      // a legend's background is what it covers (its entries past it scroll, clipped)
      const parts = [...plot.querySelectorAll('g.legend > rect.bg, text.gtitle')].filter((el) => area(box(el)) > 0);
      for (const part of parts) {
        for (const other of others) {
          // a closed <details> keeps its contents' boxes, unseen
          if (other === plot || other.contains(plot) || plot.contains(other) || !other.checkVisibility() ||
              area(box(other)) === 0) continue;
          const shared = meet(box(part), box(other));
          if (shared > 1) found.push(`${part.closest('.legend') ? 'legend' : 'title'} of the chart in ${name(plot.closest('section') ?? plot)} overlaps ${name(other)} (${Math.round(shared)} px²)`);
        }
      }
    }
    // and the charts themselves, side by side, never on one another
    for (const [i, a] of plots.entries())
      for (const b of plots.slice(i + 1))
        if (meet(box(a), box(b)) > 1) found.push(`two charts overlap in ${name(a.closest('section') ?? a)}`);
    return { found, parts: plots.length };
  });
  check(overlaps.found.length === 0,
    `no legend or title overlaps another element (${overlaps.parts} charts)${overlaps.found.length ? ':\n  ' + overlaps.found.slice(0, 10).join('\n  ') : ''}`);
  const wide = await page.evaluate(() => document.documentElement.scrollWidth);
  check(wide <= FIRST_SCREEN.width, `nothing widens the page past the window (${wide} px)`);
  mkdirSync(artifacts, { recursive: true });
  const clip = { x: 0, y: 0, ...FIRST_SCREEN };
  await page.screenshot({ path: join(artifacts, 'report-first-screen.png'), clip });
  if (process.env.PHYSBENCH_SCREENSHOT_DOCS === '1')
    await page.screenshot({ path: join(root, 'docs', 'report-first-screen.png'), clip });
  check(errors.length === 0, `the first screen loads with no error${errors.length ? ':\n  ' + errors.join('\n  ') : ''}`);
  await page.close();
}

// ---- the viewer: pixels of one engine's viewport -------------------------------------------

// fraction of a viewport's pixels that are saturated (bodies are coloured; background, ground and
// walls are grey), and a checksum of the viewport's pixels
async function viewportPixels(page, replay, view) {
  return page.evaluate(([r, v]) => {
    const replay = window.physbenchReplays[r];
    replay.render();
    const box = replay.viewport(v);
    const copy = document.createElement('canvas');
    copy.width = box.w; copy.height = box.h;
    const context = copy.getContext('2d');
    context.drawImage(replay.canvas, box.x, box.y, box.w, box.h, 0, 0, box.w, box.h);
    const pixels = context.getImageData(0, 0, box.w, box.h).data;
    let coloured = 0, sum = 0, dark = 0;
    for (let i = 0; i < pixels.length; i += 4) {
      const [red, green, blue] = [pixels[i], pixels[i + 1], pixels[i + 2]];
      if (Math.max(red, green, blue) - Math.min(red, green, blue) > 60) coloured++;
      // the contact markers' rings (0x10161c); box edges are drawn lighter (translucent)
      if (red < 30 && green < 36 && blue < 44) dark++;
      sum = (sum * 31 + red + 7 * green + 13 * blue) % 1000000007;
    }
    return { coloured: coloured / (box.w * box.h), sum, dark };
  }, [replay, view]);
}

async function setSlider(page, replay, value) {
  await page.evaluate(([r, value]) => {
    const slider = window.physbenchReplays[r].slider;
    slider.value = String(value);
    slider.dispatchEvent(new Event('input'));
  }, [replay, value]);
}

async function viewPictures(page, replay, views) {
  const pictures = [];
  for (let v = 0; v < views; v++) pictures.push(await viewportPixels(page, replay, v));
  return pictures;
}

// the tower: contact points on and off, and colouring by each body's penetration
async function contactChecks(page, replays) {
  const tower = replays.findIndex((r) => r.name === 'tower-10');
  check(tower >= 0, 'the tower-10 replay is on the page');
  if (tower < 0) return;
  const views = replays[tower].labels.length;
  const root = page.locator('.replay[data-replay]').nth(tower);
  await setSlider(page, tower, 500);
  const plain = await viewPictures(page, tower, views);
  // contact points on: every engine draws its frame's points, and their dark rings show
  await root.locator('input[type=checkbox]').check();
  const shown = await page.evaluate((r) => window.physbenchReplays[r].views.map((view) => {
    const run = view.run, j = run.contactIndexOf[view.frameAt(window.physbenchReplays[r].time)];
    return { drawn: view.contactCloud.geometry.drawRange.count, recorded: run.contactStart[j + 1] - run.contactStart[j] };
  }), tower);
  const marked = await viewPictures(page, tower, views);
  for (let v = 0; v < views; v++) {
    const label = replays[tower].labels[v];
    check(shown[v].drawn > 0 && shown[v].drawn === shown[v].recorded,
      `tower-10 ${label}: the frame's contact points are drawn (${shown[v].drawn} of ${shown[v].recorded})`);
    check(marked[v].sum !== plain[v].sum && marked[v].dark > plain[v].dark + 4 * shown[v].drawn,
      `tower-10 ${label}: contact markers change the picture (${plain[v].dark} → ${marked[v].dark} dark pixels)`);
  }
  // contact points off: the picture is the one before
  await root.locator('input[type=checkbox]').uncheck();
  const hidden = await viewPictures(page, tower, views);
  check(hidden.every((p, v) => p.sum === plain[v].sum), 'tower-10: hiding the contact points restores the picture');
  // colour by penetration: each body's colour rises with its own depth in the frame shown
  await root.locator('select').nth(1).selectOption('penetration');
  const painted = await viewPictures(page, tower, views);
  const ordered = await page.evaluate((r) => window.physbenchReplays[r].views.map((view) => {
    const n = view.run.bodies.length, j = view.run.contactIndexOf[view.frameAt(window.physbenchReplays[r].time)];
    const colours = view.boxMesh.instanceColor.array;
    const bodies = view.boxes.map(([column], i) => ({
      depth: view.run.depth[j * n + column], warmth: colours[3 * i] - colours[3 * i + 2],
    })).sort((a, b) => a.depth - b.depth);
    // never cooler with more depth, and the deepest warmer than the shallowest
    const rising = bodies.every((b, i) => i === 0 || b.warmth >= bodies[i - 1].warmth - 1e-6) &&
      bodies[bodies.length - 1].warmth > bodies[0].warmth + 1e-3;
    return { rising, spread: bodies[bodies.length - 1].depth - bodies[0].depth };
  }), tower);
  for (let v = 0; v < views; v++) {
    const label = replays[tower].labels[v];
    check(painted[v].sum !== plain[v].sum, `tower-10 ${label}: colouring by penetration changes the picture`);
    check(ordered[v].rising && ordered[v].spread > 0,
      `tower-10 ${label}: deeper bodies are warmer (depths span ${(1000 * ordered[v].spread).toFixed(2)} mm)`);
  }
  const legend = await root.locator('.replay-legend').textContent();
  check(/deepest overlap: blue 0 → red ≥ [\d.]+ mm/.test(legend), `the penetration legend reads "${legend}"`);
  mkdirSync(artifacts, { recursive: true });
  await root.locator('input[type=checkbox]').check();
  await root.scrollIntoViewIfNeeded();
  await root.screenshot({ path: join(artifacts, 'viewer-contacts.png') });
  // back to how the page started, for the screenshots that follow
  await root.locator('input[type=checkbox]').uncheck();
  await root.locator('select').nth(1).selectOption('speed');
}

// the scene file a scenario ran at its own step, as metadata.json names it
function sceneFile(results, name) {
  const info = JSON.parse(readFileSync(join(results, 'metadata.json'), 'utf8')).scenarios?.[name] ?? {};
  const files = Object.entries(info.scene_file ?? {});
  const own = files.find(([dt]) => Math.abs(Number(dt) - info.dt) <= 1e-6 * info.dt) ?? files[0];
  return own ? own[1] : join('scenes', `${name}.json`);
}

async function viewerChecks(page, results) {
  // a replay starts as it comes near the window; the checks start them all
  const atLoad = await page.evaluate(() => window.physbenchReplays.length);
  const replays = await page.evaluate(async () => (await window.physbenchStartReplays()).map((r) => ({
    name: r.data.name, labels: r.runs.map((run) => run.label), frames: r.runs.map((run) => run.frames),
  })));
  const wanted = await page.locator('.replay[data-replay]').count();
  check(replays.length === wanted && wanted > 0,
    `every replay on the page started (${replays.length} of ${wanted}; ${atLoad} near the window at load)`);
  for (const [i, replay] of replays.entries()) {
    check(replay.labels.length >= 2, `${replay.name}: two engines or more (${replay.labels.join(', ')})`);
    for (let v = 0; v < replay.labels.length; v++) {
      const { coloured } = await viewportPixels(page, i, v);
      check(coloured > 0.002, `${replay.name} ${replay.labels[v]}: bodies drawn (${(100 * coloured).toFixed(2)} % coloured pixels)`);
    }
    // the decoded poses put body 0 where the scene file starts it
    const scene = JSON.parse(readFileSync(join(results, sceneFile(results, replay.name)), 'utf8'));
    const firstDynamic = scene.bodies.findIndex((b) => b.mass > 0);
    if (firstDynamic >= 0) {
      const decoded = await page.evaluate(([r, body]) => {
        const run = window.physbenchReplays[r].runs[0];
        const column = run.bodies.indexOf(body);
        return column < 0 ? null : Array.from(run.poses.slice(column * 8, column * 8 + 3));
      }, [i, firstDynamic]);
      const start = scene.bodies[firstDynamic].position;
      const off = decoded ? Math.hypot(...decoded.map((x, k) => x - start[k])) : Infinity;
      check(off < 1e-3, `${replay.name}: body ${firstDynamic} decoded at its scene position (off by ${off.toExponential(2)} m)`);
    }
  }
  // the slider moves every engine of the tumbling box (a spinning box changes its picture)
  const tumbling = replays.findIndex((r) => r.name === 'tumbling-box');
  check(tumbling >= 0, 'the tumbling-box replay is on the page');
  if (tumbling >= 0) {
    await setSlider(page, tumbling, 0);
    const before = [];
    for (let v = 0; v < replays[tumbling].labels.length; v++) before.push((await viewportPixels(page, tumbling, v)).sum);
    await setSlider(page, tumbling, 370);
    for (let v = 0; v < replays[tumbling].labels.length; v++) {
      const after = (await viewportPixels(page, tumbling, v)).sum;
      check(after !== before[v], `tumbling-box ${replays[tumbling].labels[v]}: moving the slider changes the picture`);
    }
    const clock = await page.evaluate((r) => window.physbenchReplays[r].time, tumbling);
    check(clock > 0, `the slider moved the clock (t = ${clock.toFixed(3)} s)`);
  }
  await contactChecks(page, replays);
  // screenshots: the first replay half-way, and the tumbling box where the slider left it
  mkdirSync(artifacts, { recursive: true });
  await setSlider(page, 0, 500);
  const first = page.locator('.replay[data-replay]').first();
  await first.scrollIntoViewIfNeeded();
  await first.screenshot({ path: join(artifacts, 'viewer.png') });
  if (tumbling >= 0)
    await page.locator('.replay[data-replay]').nth(tumbling).screenshot({ path: join(artifacts, 'viewer-tumbling-box.png') });
  console.log(`screenshots in ${artifacts}`);
}

// ---- main ------------------------------------------------------------------------------------

async function main() {
  if (!existsSync(browserPath)) {
    console.log(`SKIPPED: no Chromium at ${browserPath} (scripts/setup.sh installs Debian's chromium)`);
    process.exit(77);
  }
  const browser = await chromium.launch({
    executablePath: browserPath, headless: true,
    // WebGL without a GPU: Chromium's software renderer
    args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist'],
  });
  let scratch = null;
  try {
    let pagePath = process.argv[2], results = null;
    if (pagePath && statSync(pagePath).isDirectory()) {
      results = pagePath;
      const python = process.env.PHYSBENCH_PYTHON || join(root, '.venv', 'bin', 'python');
      execFileSync(python, [join(root, 'reports', 'build_report.py'), results], { stdio: 'inherit' });
      pagePath = join(results, 'index.html');
    } else if (!pagePath) {
      const physbench = process.env.PHYSBENCH_EXE, python = process.env.PHYSBENCH_PYTHON;
      if (!physbench || !python) throw new Error('PHYSBENCH_EXE and PHYSBENCH_PYTHON must be set (CTest sets them)');
      scratch = mkdtempSync(join(tmpdir(), 'physbench-browser-'));
      results = join(scratch, 'r');
      const engines = process.env.PHYSBENCH_BROWSER_ENGINES || 'rtp,bullet';
      execFileSync(physbench, ['run', '-s', 'tower-10,tumbling-box', '-e', engines, '--no-sweep', '--duration', '1',
        '--budget', '0', '--out', results], { stdio: ['ignore', 'ignore', 'inherit'] });
      execFileSync(python, [join(root, 'reports', 'build_report.py'), results], { stdio: 'inherit' });
      pagePath = join(results, 'index.html');
    }
    const { page, errors } = await openReport(browser, pagePath);
    check(errors.length === 0, `the page loads with no JavaScript or console error${errors.length ? ':\n  ' + errors.join('\n  ') : ''}`);
    // the charts are drawn as they come near the window: at load only those near the top are
    const drawnNow = () => page.evaluate(() => {
      const divs = [...document.querySelectorAll('.plotly-graph-div')];
      return [divs.length, divs.filter((d) => d.querySelector('svg.main-svg') && d.querySelector('.trace')).length,
        divs.length ? divs[divs.length - 1].getBoundingClientRect().top : 0];
    });
    const [total, atLoad, lastTop] = await drawnNow();
    if (lastTop > 3 * 900)
      check(atLoad < total, `charts far below the window wait until they are near (${atLoad} of ${total} drawn at load)`);
    await page.evaluate(() => window.physbenchDrawCharts());
    const [plots, drawn] = await drawnNow();
    check(drawn === plots, `every chart drew (${drawn} of ${plots})`);
    await firstScreenChecks(browser, pagePath);
    await tableChecks(page);
    if (results) await viewerChecks(page, results);
    check(errors.length === 0, `no error while the table and the viewer were driven${errors.length ? ':\n  ' + errors.join('\n  ') : ''}`);
  } finally {
    await browser.close();
    if (scratch && !failures) rmSync(scratch, { recursive: true, force: true });
    else if (scratch) console.log(`results kept in ${scratch}`);
  }
  if (failures) {
    console.log(`${failures} check(s) failed`);
    process.exit(1);
  }
}

// run as a program (another script may import openReport without running the checks)
if (import.meta.url === pathToFileURL(process.argv[1]).href)
  main().catch((error) => { console.error(error); process.exit(1); });
