// The report's full results table (templates/results_table.html.j2): sorting by a click on a
// column header is tablesort's (npm "tablesort"); this file adds the sort for measured values and
// the filters, a text box and a select each for engine and status.
//
// A numeric cell carries its value in data-sort (the text is rounded, "1.2e+05"); an empty cell
// an empty data-sort, and it stays below every value in either direction: the run had no such
// measurement, which is not a measurement of nothing.
import Tablesort from 'tablesort';

// tablesort sorts descending with the method's comparison and reverses it for ascending; the
// header being sorted carries the direction in aria-sort by the time the comparison runs (the
// table announces the sort, beforeSort, just before it sets aria-sort)
let sorting = null;

function ascending() {
  return sorting?.querySelector('th[aria-sort]')?.getAttribute('aria-sort') === 'ascending';
}

// the columns whose header says data-sort-method="value" (never chosen by looking at the cells)
Tablesort.extend('value', () => false, (a, b) => {
  const x = a === '' ? NaN : Number(a), y = b === '' ? NaN : Number(b);
  if (Number.isNaN(x) || Number.isNaN(y)) {
    if (Number.isNaN(x) && Number.isNaN(y)) return 0;
    // an empty cell ends up last: after the reversal for ascending, and without it for descending
    const last = Number.isNaN(x) ? 1 : -1;
    return ascending() ? -last : last;
  }
  return y - x;
});

// every word of the query in the row's text, and the row's engine and status as selected
function applyFilters(table, controls) {
  const words = controls.text.value.toLowerCase().split(/\s+/).filter(Boolean);
  const engine = controls.engine.value, status = controls.status.value;
  let shown = 0;
  const rows = table.tBodies[0].rows;
  for (const row of rows) {
    const text = row.textContent.toLowerCase();
    const match = words.every((w) => text.includes(w)) &&
      (!engine || row.dataset.engine === engine) && (!status || row.dataset.status === status);
    row.hidden = !match;
    if (match) shown++;
  }
  controls.count.textContent = `${shown} of ${rows.length} runs shown`;
}

function startTable(table) {
  table.addEventListener('beforeSort', () => { sorting = table; });
  new Tablesort(table);
  const box = document.getElementById(table.dataset.controls);
  const controls = {
    text: box.querySelector('input[type=search]'), engine: box.querySelector('select[name=engine]'),
    status: box.querySelector('select[name=status]'), count: box.querySelector('.table-count'),
  };
  for (const control of [controls.text, controls.engine, controls.status])
    control.addEventListener('input', () => applyFilters(table, controls));
  applyFilters(table, controls);
  box.hidden = false;
  table.classList.add('sortable');
}

for (const table of document.querySelectorAll('table[data-controls]')) startTable(table);
