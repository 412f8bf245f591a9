// Starts Foxglove Studio (studio-base's App, whose exports the UMD bundle put on window) with one layout, in memory:
// a 3-D panel following "map", seen from above, with sextant's topics visible.  The data source comes from the
// page's URL (?ds=foxglove-websocket&ds.url=ws://...), as in Foxglove's own web app.
const panelId = "3D!sextant";
const topics = ["/sextant/trajectories", "/sextant/landmark_map", "/sextant/frames", "/sextant/landmarks",
  "/sextant/targets", "/sextant/truth"];
const panel = {
  followTf: "map",
  followMode: "follow-none",
  cameraState: { distance: 62, perspective: false, phi: 0, thetaOffset: 0, target: [0, 0, 0], targetOffset: [0, 0, 0],
    targetOrientation: [0, 0, 0, 1], fovy: 45, near: 0.5, far: 5000 },
  scene: { transforms: { showLabel: true, axisScale: 1.5 }, labelScaleFactor: 1 },
  transforms: {},
  topics: Object.fromEntries(topics.map((t) => [t, { visible: true }])),
  layers: { grid: { layerId: "foxglove.Grid", visible: true, size: 100, divisions: 10, color: "#3a3a4a" } },
  publish: { type: "point", poseTopic: "/move_base_simple/goal", pointTopic: "/clicked_point",
    poseEstimateTopic: "/initialpose", poseEstimateXDeviation: 0.5, poseEstimateYDeviation: 0.5,
    poseEstimateThetaDeviation: 0.26 },
  imageMode: {},
};
const data = { configById: { [panelId]: panel }, globalVariables: {}, userNodes: {}, linkedGlobalVariables: [],
  playbackConfig: { speed: 1 }, layout: panelId };
const now = new Date().toISOString();
const layout = { id: "sextant", name: "sextant", permission: "CREATOR_WRITE", baseline: { data, savedAt: now },
  working: undefined, syncInfo: undefined };
const layoutStorage = {
  list: async () => [layout],
  get: async (_namespace, id) => (id === layout.id ? layout : undefined),
  put: async (_namespace, l) => l,
  delete: async () => {},
  importLayouts: async () => {},
};
const settings = new Map([["launchPreference", "web"], ["colorScheme", "dark"]]);
const appConfiguration = {
  get: (key) => settings.get(key),
  set: async (key, value) => void settings.set(key, value),
  addChangeListener: () => {},
  removeChangeListener: () => {},
};
void initI18n().then(() =>
  ReactDOM.render(
    React.createElement(App, {
      deepLinks: [window.location.href],
      appConfiguration,
      dataSources: [new FoxgloveWebSocketDataSourceFactory(), new RemoteDataSourceFactory()],
      layoutStorage,
      extensionLoaders: [],
      enableGlobalCss: true,
    }),
    document.getElementById("root"),
  ),
);
