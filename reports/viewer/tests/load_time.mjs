// How long a built report takes to open in headless Chromium as a reader's browser would: from
// navigation to the page's load event and, on a page with replays, to the viewer's ready flag.
// Prints seconds; a measurement, not a test.
//   node reports/viewer/tests/load_time.mjs RESULTS/index.html
import { chromium } from 'playwright-core';
import { openReport } from './report_browser.mjs';

const page_path = process.argv[2];
if (!page_path) {
  console.error('usage: node load_time.mjs PAGE.html');
  process.exit(2);
}
const browser = await chromium.launch({ executablePath: process.env.PHYSBENCH_CHROMIUM || '/usr/bin/chromium' });
const started = performance.now();
const { errors } = await openReport(browser, page_path);
const seconds = (performance.now() - started) / 1000;
await browser.close();
console.log(`${page_path}: opened in ${seconds.toFixed(2)} s${errors.length ? `, ${errors.length} error(s): ${errors[0]}` : ''}`);
