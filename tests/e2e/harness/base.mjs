// What every part of the harness shares: the repository's root and a sleep.
import path from 'node:path';
import { fileURLToPath } from 'node:url';

export const ROOT = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../../..');

export const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
