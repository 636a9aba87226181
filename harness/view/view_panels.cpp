// gibench view: the panels right of the image (docs/commands.md "gibench
// view", "Panels"), drawn with Dear ImGui (Debian's libimgui, its GLFW and
// OpenGL 3 backends): the method and its parameters, the second method of
// the split, what the image shows, the frame time graph and stage times,
// the reference's progress with the live relMSE, and the pixel read-out.
// A widget's change is done after the frame is drawn (apply()), through
// the same functions as the keys and the script lines.
extern "C" {
#include "view.h"
#include "view_panels.h"
}

#include "imgui.h"
#include "backends/imgui_impl_glfw.h"
#include "backends/imgui_impl_opengl3.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>

// What the widgets asked for in a frame; done by the main loop after it
// (view_panels_apply), not while a frame is drawn.
struct actions {
    int method = -3, second = -3, split = -1, source = -1, buffer = -1, reset_zoom = 0;
    char param[160] = "";
};

struct view_panels {
    actions pending;
    int has_pending;
    int ready;
    // edits of the parameter widgets, per parameter, before they apply
    double values[64];
    const gi_params *values_of;
};

namespace
{

const char *method_name(void *data, int i)
{
    const viewer *v = static_cast<const viewer *>(data);
    return i < (int)v->reg->count ? v->reg->items[i].method->id : "reference";
}

bool method_item(void *data, int i, const char **out)
{
    *out = method_name(data, i);
    return true;
}

bool second_item(void *data, int i, const char **out)
{
    *out = i == 0 ? "(none)" : method_name(data, i - 1);
    return true;
}

bool buffer_item(void *data, int i, const char **out)
{
    const char *n = view_buffer_name(static_cast<const viewer *>(data), (uint32_t)i);
    *out = n ? n : "?";
    return true;
}

// One parameter's widget, per its type and range; a finished edit goes to a->param.
void param_widget(viewer *v, view_panels *p, uint32_t i, actions *a)
{
    const gi_param_desc *d = &v->params->desc[i];
    double &x = p->values[i];
    bool done = false;
    char label[96];
    std::snprintf(label, sizeof label, "%s##p%u", d->name, i);
    switch (d->type) {
    case GI_PARAM_INT: {
        int k = (int)x;
        bool log = d->max / (d->min > 0 ? d->min : 1) > 64;
        if (ImGui::SliderInt(label, &k, (int)d->min, (int)d->max, "%d",
                             log ? ImGuiSliderFlags_Logarithmic : 0))
            x = k;
        done = ImGui::IsItemDeactivatedAfterEdit();
        break;
    }
    case GI_PARAM_FLOAT: {
        float f = (float)x;
        bool log = d->min > 0 && d->max / d->min > 64;
        if (ImGui::SliderFloat(label, &f, (float)d->min, (float)d->max, "%.4g",
                               log ? ImGuiSliderFlags_Logarithmic : 0))
            x = f;
        done = ImGui::IsItemDeactivatedAfterEdit();
        break;
    }
    case GI_PARAM_BOOL: {
        bool b = x != 0;
        if (ImGui::Checkbox(label, &b)) {
            x = b;
            done = true;
        }
        break;
    }
    case GI_PARAM_ENUM: {
        char items[512];
        std::snprintf(items, sizeof items - 1, "%s", d->choices ? d->choices : "");
        size_t n = std::strlen(items);
        for (size_t c = 0; c < n; c++)
            if (items[c] == '|')
                items[c] = '\0';
        items[n + 1] = '\0'; // Combo's list ends with an empty item
        int k = (int)x;
        if (ImGui::Combo(label, &k, items)) {
            x = k;
            done = true;
        }
        break;
    }
    }
    if (d->help && ImGui::IsItemHovered())
        ImGui::SetTooltip("%s%s%s", d->symbol ? d->symbol : "", d->symbol ? ": " : "", d->help);
    if (!done)
        return;
    if (d->type == GI_PARAM_ENUM) {
        char choice[128];
        gi_param_choice(d, (int)x, choice, sizeof choice);
        std::snprintf(a->param, sizeof a->param, "%s=%s", d->name, choice);
    } else if (d->type == GI_PARAM_BOOL) {
        std::snprintf(a->param, sizeof a->param, "%s=%s", d->name, x != 0 ? "true" : "false");
    } else {
        std::snprintf(a->param, sizeof a->param, "%s=%.9g", d->name, x);
    }
}

void method_section(viewer *v, actions *a)
{
    int n = (int)v->reg->count;
    int cur = v->method_index < 0 ? n : v->method_index;
    if (ImGui::Combo("method", &cur, method_item, v, n + 1))
        a->method = cur == n ? -1 : cur;
    if (v->status[0])
        ImGui::TextWrapped("%s", v->status);
}

// The method's parameters, last: a paper's table can be long.
void param_section(viewer *v, view_panels *p, actions *a)
{
    if (v->method_index < 0 || !v->params) {
        ImGui::TextDisabled("the reference has no parameters");
        return;
    }
    if (p->values_of != v->params) { // a new instance: its values
        for (uint32_t i = 0; i < v->params->count && i < 64; i++)
            p->values[i] = v->params->values[i];
        p->values_of = v->params;
    }
    for (uint32_t i = 0; i < v->params->count && i < 64; i++)
        param_widget(v, p, i, a);
}

void view_section(viewer *v, actions *a)
{
    static const char *sources = "output\0error\0reference\0buffer\0";
    int src = v->source;
    if (ImGui::Combo("show", &src, sources))
        a->source = src;
    uint32_t nb = view_buffer_count(v);
    if (nb) {
        int b = v->buffer_sel;
        if (ImGui::Combo("buffers", &b, buffer_item, v, (int)nb))
            a->buffer = b;
    } else {
        const char *none[] = {"(none)"};
        int b = 0;
        ImGui::Combo("buffers", &b, none, 1);
    }
    static const char *splits = "off\0reference\0error\0second method\0";
    int sp = v->split;
    if (ImGui::Combo("split", &sp, splits))
        a->split = sp;
    int n = (int)v->reg->count;
    int cur = v->second.method_index < 0 ? 0 : v->second.method_index + 1;
    if (ImGui::Combo("second", &cur, second_item, v, n + 1))
        a->second = cur - 1;
    ImGui::Text("zoom %.3gx  pan %.1f, %.1f", (double)v->zoom, (double)v->pan_x, (double)v->pan_y);
    ImGui::SameLine();
    if (ImGui::SmallButton("reset (Z)"))
        a->reset_zoom = 1;
}

void timing_section(viewer *v)
{
    uint32_t n = v->frame_hist_n < VIEW_FRAME_HISTORY ? v->frame_hist_n : VIEW_FRAME_HISTORY;
    float ms[VIEW_FRAME_HISTORY];
    float top = 0;
    for (uint32_t i = 0; i < n; i++) { // oldest first
        uint32_t k = (v->frame_hist_n - n + i) % VIEW_FRAME_HISTORY;
        ms[i] = (float)v->frame_hist[k];
        top = ms[i] > top ? ms[i] : top;
    }
    char over[64];
    std::snprintf(over, sizeof over, "%.2f ms/frame", v->frame_ms);
    ImGui::PlotLines("##frames", ms, (int)n, 0, over, 0.0f, top * 1.1f + 1e-3f,
                     ImVec2(VIEW_PANEL_W - 20, 60));
    ImGui::Text("frame %u  prepare %.0f ms  ui %.1f ms", v->frame_index, v->prepare_ms,
                v->display_ms);
    for (int i = 0; i < v->stage_count; i++)
        ImGui::Text("  %-22s %8.3f ms", v->stage_name[i], v->stage_ms[i]);
}

void reference_section(viewer *v)
{
    ImGui::Text("reference: %llu spp%s", (unsigned long long)v->ref_spp,
                view_ref_running(&v->ref) ? " (running)" : "");
    view_error_update(v, 0);
    if (v->method_index >= 0 && !std::isnan(v->relmse))
        ImGui::Text("relMSE %.5g (at %llu spp)", v->relmse, (unsigned long long)v->err_spp);
    else
        ImGui::TextDisabled("relMSE: no reference pass yet");
}

void pixel_section(viewer *v)
{
    if (v->cursor_px < 0) {
        ImGui::TextDisabled("pixel: move the mouse over the image");
        return;
    }
    view_pixel_readout(v, v->cursor_px, v->cursor_py);
    ImGui::Text("pixel %d, %d", v->cursor_px, v->cursor_py);
    ImGui::Text("method  %.4g %.4g %.4g", (double)v->px_method[0], (double)v->px_method[1],
                (double)v->px_method[2]);
    ImGui::Text("ref     %.4g %.4g %.4g", (double)v->px_ref[0], (double)v->px_ref[1],
                (double)v->px_ref[2]);
    ImGui::Text("rel err %.4g", (double)v->px_err);
}

// The widgets' requests, through the functions of the keys and script lines.
int apply(viewer *v, const actions &a)
{
    int rc = EXIT_OK;
    if (a.method > -3) {
        if (a.method >= 0)
            v->last_method = a.method;
        rc = view_select(v, a.method);
    }
    if (rc == EXIT_OK && a.param[0])
        rc = view_set_param(v, a.param);
    if (rc == EXIT_OK && a.second > -3)
        rc = view_second_select(v, a.second);
    if (a.split >= 0) {
        v->split = a.split == 3 && v->second.method_index < 0 ? 0 : a.split;
        view_reference_as_needed(v);
    }
    if (a.source >= 0)
        v->source = a.source;
    if (a.buffer >= 0) {
        v->buffer_sel = a.buffer;
        view_buffer_upload(v);
    }
    if (a.reset_zoom)
        view_zoom_reset(v);
    v->need_display = 1;
    return rc;
}

} // namespace

extern "C" {

int view_panels_init(viewer *v)
{
    if (v->panels)
        return v->panels->ready;
    view_panels *p = static_cast<view_panels *>(std::calloc(1, sizeof *p));
    if (!p)
        return 0;
    v->panels = p;
    IMGUI_CHECKVERSION();
    ImGui::CreateContext();
    ImGui::GetIO().IniFilename = nullptr; // no imgui.ini in the working directory
    ImGui::StyleColorsDark();
    // the viewer's callbacks pass the events on (view_input.c)
    if (!ImGui_ImplGlfw_InitForOpenGL(v->win, false))
        return 0;
    p->ready = 1;
    return ImGui_ImplOpenGL3_Init("#version 450 core") ? 1 : 0;
}

void view_panels_free(viewer *v)
{
    if (!v->panels)
        return;
    if (v->panels->ready) {
        ImGui_ImplOpenGL3_Shutdown();
        ImGui_ImplGlfw_Shutdown();
        ImGui::DestroyContext();
    }
    std::free(v->panels);
    v->panels = nullptr;
}

int view_panels_want_mouse(const viewer *v)
{
    return v->panels && v->panels->ready && ImGui::GetIO().WantCaptureMouse;
}

int view_panels_want_keyboard(const viewer *v)
{
    return v->panels && v->panels->ready && ImGui::GetIO().WantTextInput;
}

void view_panels_button(GLFWwindow *w, int button, int action, int mods)
{
    if (ImGui::GetCurrentContext())
        ImGui_ImplGlfw_MouseButtonCallback(w, button, action, mods);
}

void view_panels_scroll(GLFWwindow *w, double dx, double dy)
{
    if (ImGui::GetCurrentContext())
        ImGui_ImplGlfw_ScrollCallback(w, dx, dy);
}

void view_panels_key(GLFWwindow *w, int key, int scancode, int action, int mods)
{
    if (ImGui::GetCurrentContext())
        ImGui_ImplGlfw_KeyCallback(w, key, scancode, action, mods);
}

void view_panels_char(GLFWwindow *w, unsigned int c)
{
    if (ImGui::GetCurrentContext())
        ImGui_ImplGlfw_CharCallback(w, c);
}

void view_panels_draw(viewer *v)
{
    if (!v->panels && !view_panels_init(v)) { // first shown with key F1 or script line panels
        std::fprintf(stderr, "gibench: view: Dear ImGui could not start; the panels stay empty\n");
        v->show_panels = 0;
        return;
    }
    view_panels *p = v->panels;
    if (!p->ready)
        return;
    double t0 = gi_now();
    ImGui_ImplOpenGL3_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    ImGui::NewFrame();
    ImGui::SetNextWindowPos(ImVec2((float)v->image_w, 0));
    ImGui::SetNextWindowSize(ImVec2((float)VIEW_PANEL_W, (float)v->image_h));
    ImGui::Begin("gibench view", nullptr,
                 ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse |
                     ImGuiWindowFlags_NoSavedSettings);
    ImGui::PushItemWidth(VIEW_PANEL_W * 0.55f);
    actions a;
    if (ImGui::CollapsingHeader("Method", ImGuiTreeNodeFlags_DefaultOpen))
        method_section(v, &a);
    if (ImGui::CollapsingHeader("Reference and error", ImGuiTreeNodeFlags_DefaultOpen))
        reference_section(v);
    if (ImGui::CollapsingHeader("Pixel", ImGuiTreeNodeFlags_DefaultOpen))
        pixel_section(v);
    if (ImGui::CollapsingHeader("Frame time", ImGuiTreeNodeFlags_DefaultOpen))
        timing_section(v);
    if (ImGui::CollapsingHeader("View", ImGuiTreeNodeFlags_DefaultOpen))
        view_section(v, &a);
    if (ImGui::CollapsingHeader("Parameters", ImGuiTreeNodeFlags_DefaultOpen))
        param_section(v, p, &a);
    ImGui::PopItemWidth();
    ImGui::End();
    ImGui::Render();
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
    v->overlay_ms = 1e3 * (gi_now() - t0);
    bool asked = a.method > -3 || a.second > -3 || a.split >= 0 || a.source >= 0 || a.buffer >= 0 ||
                 a.reset_zoom || a.param[0];
    if (asked) {
        p->pending = a;
        p->has_pending = 1;
    }
}

void view_panels_apply(viewer *v)
{
    view_panels *p = v->panels;
    if (!p || !p->has_pending)
        return;
    p->has_pending = 0;
    if (apply(v, p->pending) != EXIT_OK)
        v->status_error = 1; // interactive: the message was printed; keep running
}

} // extern "C"
