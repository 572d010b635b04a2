import { defineConfig } from "vite";

// The hub serves `dist/` at `/`; relative asset URLs also let it sit behind a
// reverse proxy under a sub-path. `npm run dev` proxies the API to a local hub.
const HUB = "http://127.0.0.1:8000";

export default defineConfig({
  base: "./",
  build: {
    outDir: "dist",
    emptyOutDir: true,
    sourcemap: true,
  },
  server: {
    proxy: {
      "/api": { target: HUB, ws: true },
    },
  },
});
