"""The layer rules: the app's role layers, the crate rules and LAYER_ALLOW."""

from .case import CrateCase, ig


class LayerRules(CrateCase):
    """LAYERS and CRATE_RULES on a small workspace laid out like ours: core/src,
    core/mark/src, core/cli/src, app/src (the default roots)."""

    CORE = {
        "core/src/lib.rs": "pub mod json;\npub mod vo;\npub use vo::Pose;\n",
        "core/src/json.rs": "pub struct Json;\npub fn parse() {}\n",
        "core/src/vo/mod.rs": "mod pose;\npub use pose::Pose;\npub fn run() {}\n",
        "core/src/vo/pose.rs": "pub struct Pose;\n",
        "core/mark/src/lib.rs": "use siftlab_core::json::Json;\npub fn mark(_: Json) {}\n",
        "core/cli/src/lib.rs": "pub fn cli() { siftlab_mark::mark(siftlab_core::json::Json) }\n",
    }
    APP = {
        "app/src/lib.rs": "pub mod model;\npub mod page;\npub mod platform;\npub mod protocol;\n"
                          "pub mod services;\npub mod worker;\npub use page::App;\n",
        "app/src/page/mod.rs": "mod odometry;\npub struct App;\n",
        "app/src/page/odometry/mod.rs": "mod frame;\n",
        "app/src/page/odometry/frame.rs": "use crate::services::load;\nuse crate::model::Lab;\n"
                                          "use crate::protocol::Req;\nfn f(_: Lab, _: Req) { load(); crate::platform::now_ms(); }\n",
        "app/src/services/mod.rs": "use crate::model::Lab;\nuse crate::protocol::Req;\n"
                                   "pub fn load() { crate::platform::now_ms(); }\nfn g(_: Lab, _: Req) {}\n",
        "app/src/model/mod.rs": "use crate::protocol::Req;\npub struct Lab;\nfn h(_: Req) {}\n",
        "app/src/protocol/mod.rs": "pub struct Req;\n",
        "app/src/worker/mod.rs": "use crate::protocol::Req;\nuse crate::model::Lab;\npub const NAME: &str = \"w\";\n"
                                 "fn k(_: Req, _: Lab) {}\n",
        "app/src/platform.rs": "pub fn now_ms() -> f64 { 0.0 }\n",
    }

    def setUp(self):
        super().setUp()
        self._allow = ig.LAYER_ALLOW
        ig.LAYER_ALLOW = set()

    def tearDown(self):
        ig.LAYER_ALLOW = self._allow
        super().tearDown()

    def check(self, **changed):
        """Writes the workspace with `changed` (path with / as __) over it; (exit code, the
        violation lines)."""
        files = {**self.CORE, **self.APP}
        for key, text in changed.items():
            files[key.replace("__", "/")] = text
        self.write(files)
        code, out, _ = self.run_cli()
        return code, [l for l in out.splitlines() if l.startswith(("LAYER RULE BROKEN", "allowed for now"))]

    def assertBroken(self, lines, file, line, what, rule):
        self.assertIn(f"LAYER RULE BROKEN: {file}:{line}: {what}: {rule}", lines)

    def test_the_layers_as_they_should_be_pass(self):
        code, lines = self.check()
        self.assertEqual((code, lines), (0, []))

    def test_page_may_not_import_worker(self):
        code, lines = self.check(**{"app__src__page__odometry__frame.rs":
                                    "fn f() -> &'static str { crate::worker::NAME }\n"})
        self.assertEqual(code, 1)
        self.assertBroken(lines, "app/src/page/odometry/frame.rs", 1, "imports NAME from app/src/worker/mod.rs",
                          "page may import services, model, protocol, platform, not worker "
                          "(layers: page -> services -> model -> protocol)")

    def test_services_may_not_import_page_or_worker(self):
        code, lines = self.check(**{"app__src__services__mod.rs":
                                    "use crate::page::App;\npub fn load(_: App) { crate::worker::NAME; }\n"})
        self.assertEqual(code, 1)
        rule = "services may import model, protocol, platform, not {} (layers: page -> services -> model -> protocol)"
        self.assertBroken(lines, "app/src/services/mod.rs", 1, "imports App from app/src/page/mod.rs",
                          rule.format("page"))
        self.assertBroken(lines, "app/src/services/mod.rs", 2, "imports NAME from app/src/worker/mod.rs",
                          rule.format("worker"))

    def test_model_may_import_protocol_only(self):
        code, lines = self.check(**{"app__src__model__mod.rs":
                                    "use crate::protocol::Req;\npub struct Lab;\n"
                                    "fn h(_: Req) { crate::platform::now_ms(); crate::services::load(); }\n"})
        self.assertEqual(code, 1)
        rule = "model may import protocol, not {} (layers: page -> services -> model -> protocol)"
        self.assertBroken(lines, "app/src/model/mod.rs", 3, "imports now_ms from app/src/platform.rs",
                          rule.format("platform"))
        self.assertBroken(lines, "app/src/model/mod.rs", 3, "imports load from app/src/services/mod.rs",
                          rule.format("services"))
        self.assertEqual(len(lines), 2)

    def test_protocol_imports_no_other_layer(self):
        code, lines = self.check(**{"app__src__protocol__mod.rs": "pub struct Req(crate::model::Lab);\n"})
        self.assertEqual(code, 1)
        self.assertBroken(lines, "app/src/protocol/mod.rs", 1, "imports Lab from app/src/model/mod.rs",
                          "protocol may import no other app layer, not model "
                          "(layers: page -> services -> model -> protocol)")

    def test_worker_may_import_protocol_model_and_platform_only(self):
        code, lines = self.check(**{"app__src__worker__mod.rs":
                                    "use crate::protocol::Req;\nuse crate::model::Lab;\nfn k(_: Req, _: Lab) {\n"
                                    "    crate::platform::now_ms();\n    crate::services::load();\n}\n"})
        self.assertEqual(code, 1)
        rule = "worker may import protocol, model, platform, not {} (layers: page -> services -> model -> protocol)"
        self.assertBroken(lines, "app/src/worker/mod.rs", 5, "imports load from app/src/services/mod.rs",
                          rule.format("services"))
        self.assertEqual(len(lines), 1)

    def test_platform_imports_no_other_layer(self):
        code, lines = self.check(**{"app__src__platform.rs":
                                    "pub fn now_ms() -> f64 { 0.0 }\npub fn f(_: crate::protocol::Req) {}\n"})
        self.assertEqual(code, 1)
        self.assertBroken(lines, "app/src/platform.rs", 2, "imports Req from app/src/protocol/mod.rs",
                          "platform may import no other app layer, not protocol "
                          "(layers: page -> services -> model -> protocol)")

    def test_lib_may_name_every_layer_and_a_new_top_level_module_needs_a_layer(self):
        code, lines = self.check(**{
            "app__src__lib.rs": self.APP["app/src/lib.rs"] + "pub mod util;\n"
                                "pub fn start() { crate::worker::NAME; services::load(); }\n",
            "app__src__util.rs": "pub fn u(_: crate::model::Lab) {}\n"})
        self.assertEqual(code, 1)
        self.assertEqual(lines, ["LAYER RULE BROKEN: app/src/util.rs:1: imports Lab from app/src/model/mod.rs: "
                                 "every file of app/src is in a layer: page, services, model, protocol, worker, "
                                 "platform, lib"])

    def test_allow_list_lets_a_listed_import_through_and_names_stale_entries(self):
        ig.LAYER_ALLOW = {("app/src/model/mod.rs", "now_ms"), ("app/src/model/mod.rs", "gone")}
        code, lines = self.check(**{"app__src__model__mod.rs": "pub struct Lab;\nfn h() { crate::platform::now_ms(); }\n"})
        self.assertEqual(code, 0)
        self.assertEqual(lines, ["allowed for now (LAYER_ALLOW): app/src/model/mod.rs:2: imports now_ms from "
                                 "app/src/platform.rs: model may import protocol, not platform "
                                 "(layers: page -> services -> model -> protocol)"])
        _, out, _ = self.run_cli()
        self.assertIn("note: LAYER_ALLOW lets app/src/model/mod.rs import gone, which breaks no rule now", out)

    MARK_RULE = "siftlab-mark never reaches core's vo module (siftlab_core::vo, core/src/vo/)"

    def test_mark_never_reaches_core_vo(self):
        code, lines = self.check(**{"core__mark__src__lib.rs": """\
            use siftlab_core::json::Json;
            use siftlab_core::vo::run;
            use siftlab_core::{json, vo};
            pub fn mark(_: Json) { run(); json::parse(); }
            fn a() { siftlab_core::vo::run(); }
            fn b(_: siftlab_core::Pose) {}
            fn c() { ::siftlab_core::vo::run(); }
            """})
        self.assertEqual(code, 1)
        f = "core/mark/src/lib.rs"
        self.assertBroken(lines, f, 2, "imports siftlab_core::vo::run (core/src/vo/mod.rs)", self.MARK_RULE)
        self.assertBroken(lines, f, 3, "imports siftlab_core::vo (core/src/vo/mod.rs)", self.MARK_RULE)
        self.assertBroken(lines, f, 5, "imports siftlab_core::vo::run (core/src/vo/mod.rs)", self.MARK_RULE)
        # A re-export at core's root is followed to the file that defines it.
        self.assertBroken(lines, f, 6, "imports siftlab_core::Pose (core/src/vo/pose.rs)", self.MARK_RULE)
        self.assertBroken(lines, f, 7, "imports siftlab_core::vo::run (core/src/vo/mod.rs)", self.MARK_RULE)
        self.assertEqual(len(lines), 5, lines)

    def test_mark_reaches_vo_through_an_alias_or_a_glob(self):
        code, lines = self.check(**{"core__mark__src__lib.rs": """\
            use siftlab_core as core;
            pub fn mark() { core::vo::run(); }
            mod g {
                use siftlab_core::*;
                fn f(_: json::Json) { vo::run(); }
                fn p(_: Pose) {}
            }
            """})
        self.assertEqual(code, 1)
        f = "core/mark/src/lib.rs"
        self.assertBroken(lines, f, 2, "imports siftlab_core::vo::run (core/src/vo/mod.rs)", self.MARK_RULE)
        self.assertBroken(lines, f, 5, "imports siftlab_core::vo::run (core/src/vo/mod.rs)", self.MARK_RULE)
        self.assertBroken(lines, f, 6, "imports siftlab_core::Pose (core/src/vo/pose.rs)", self.MARK_RULE)
        self.assertEqual(len(lines), 3, lines)

    def test_core_never_imports_mark_or_cli(self):
        code, lines = self.check(**{"core__src__json.rs": """\
            use siftlab_mark::mark;
            pub struct Json;
            pub fn parse() { mark(Json); siftlab_cli::cli(); }
            """})
        self.assertEqual(code, 1)
        self.assertEqual(lines, [
            "LAYER RULE BROKEN: core/src/json.rs:1: imports siftlab_mark::mark: siftlab-core never imports siftlab-mark",
            "LAYER RULE BROKEN: core/src/json.rs:3: imports siftlab_cli::cli: siftlab-core never imports siftlab-cli",
        ])
