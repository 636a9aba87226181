/* gibench view: zoom and pan of the image (docs/commands.md "gibench
 * view"). The image region is the window left of the panels; a window
 * pixel (x, y) of it shows image pixel (pan_x + x / zoom, pan_y + y / zoom).
 * Zoom and pan only change what is shown: the method and the reference
 * keep rendering the whole image at the region's size. */
#include "view.h"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <math.h>

#define ZOOM_MIN 0.25f
#define ZOOM_MAX 64.0f

/* The image region's size in window pixels: the window less the panels. */
void view_region_update(viewer *v)
{
    int ww = 0, wh = 0;
    glfwGetWindowSize(v->win, &ww, &wh);
    int pw = v->show_panels ? VIEW_PANEL_W : 0;
    v->image_w = ww - pw > 1 ? ww - pw : 1;
    v->image_h = wh > 1 ? wh : 1;
}

/* The window's pixels per image pixel at zoom 1: the region maps onto the
 * image (the same size, but for the window manager's rounding). */
static double base_scale(const viewer *v)
{
    return (double)v->width / (double)(v->image_w > 0 ? v->image_w : 1);
}

int view_to_image(const viewer *v, double x, double y, double *ix, double *iy)
{
    double s = base_scale(v) / (double)v->zoom;
    *ix = v->pan_x + x * s;
    *iy = v->pan_y + y * s;
    return x >= 0 && x < v->image_w && y >= 0 && y < v->image_h && *ix >= 0 &&
           *ix < (double)v->width && *iy >= 0 && *iy < (double)v->height;
}

void view_zoom_at(viewer *v, float f, double x, double y)
{
    double ix, iy;
    view_to_image(v, x, y, &ix, &iy);
    v->zoom = fminf(ZOOM_MAX, fmaxf(ZOOM_MIN, v->zoom * f));
    /* the image point under (x, y) stays there */
    double s = base_scale(v) / (double)v->zoom;
    v->pan_x = (float)(ix - x * s);
    v->pan_y = (float)(iy - y * s);
    v->need_display = 1;
}

void view_pan(viewer *v, double dx, double dy)
{
    double s = base_scale(v) / (double)v->zoom;
    v->pan_x -= (float)(dx * s);
    v->pan_y -= (float)(dy * s);
    v->need_display = 1;
}

void view_zoom_reset(viewer *v)
{
    v->zoom = 1.0f;
    v->pan_x = v->pan_y = 0.0f;
    v->need_display = 1;
}
