mod camera;
mod pixels;
mod scene;
mod surfaces;
mod viewer;
